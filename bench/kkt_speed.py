"""Median wall time of nhham.simulate (the compiled DOP853 loop and its diagnostics) and of
the rhs (one state, a batch of 10^4) on the Whipple bicycle and the 8-link snake, in this
process: run it once on each tree to compare (bench/RESULTS.md, issue 33 item 3).
``--accuracy``: the relative error of x_dot(1) - 1/2 against 1/(a + b) on
examples/mass_ratio.toml at b/a = 1e0 .. 1e16 (a b = 1), DOP853 and rk4, C backend."""
import statistics
import sys
import time
import warnings

import numpy as np

import nhham
from nhham.system.models import snake

warnings.simplefilter("ignore")


def accuracy():
    system = nhham.load_scene("examples/mass_ratio.toml").system
    base = nhham.numeric_model(system, backend="c")
    print("| b/a | DOP853 rtol 1e-13 | rk4 h = 0.01 |\n|---|---|---|")
    for e in range(0, 17, 2):
        a, b = 10.0 ** (-e / 2), 10.0 ** (e / 2)
        model = base.with_parameters(a=a, b=b)
        errs = []
        for method, opts in (("DOP853", {"rtol": 1e-13}), ("rk4", {"step": 0.01})):
            r = nhham.simulate(model, (0, 1), [0.0, 0.0, 0.5, 0.5], method=method, warn=False,
                               **opts)
            errs.append(abs(r["x_dot"][-1] - 0.5 - 1 / (a + b)) * (a + b))
        print(f"| 1e{e} | {errs[0]:.2e} | {errs[1]:.2e} |")


if "--accuracy" in sys.argv:
    accuracy()
    sys.exit()

def med(fn, k):
    out = []
    for _ in range(k):
        t = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t)
    return statistics.median(out)

sc = nhham.load_scene("examples/whipple_bicycle.toml")
bike = nhham.numeric_model(sc.system, backend="c")
y0 = bike.state(sc.initial)
sn = nhham.numeric_model(snake(8), backend="c")
rng = np.random.default_rng(0)
ys = np.concatenate([rng.uniform(-0.5, 0.5, sn.n), rng.normal(size=sn.n)])
ys[2:sn.n] = 0.3 * np.cumsum(rng.uniform(-0.4, 0.4, sn.n - 2))
ys = sn.project(ys).y
Yb = np.tile(y0, (10000, 1))
Ys = np.tile(ys, (10000, 1))
rows = []
for name, model, y, Y in (("bicycle", bike, y0, Yb), ("snake8", sn, ys, Ys)):
    sim = med(lambda: nhham.simulate(model, (0, 10), y, method="DOP853", rtol=1e-10, warn=False), 15)
    batch = med(lambda: model.rhs(0.0, Y), 15) / len(Y)
    one = med(lambda: [model.rhs(0.0, y) for _ in range(2000)], 9) / 2000
    rows.append(f"{name}: simulate DOP853 rtol 1e-10 t=10 {1e3*sim:.2f} ms; rhs() {1e6*one:.2f} us; batch rhs {1e6*batch:.3f} us/state")
print("\n".join(rows))
