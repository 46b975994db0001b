"""Which solve gives the constrained accelerations, and how well, on the example scenes
and on the model problem in three units (issue 43, item 8: a decision free of units).

For each scene: a 10 s run's states (the scene's ``[initial]``; 60 s at most a scene),
then at every state the accelerations of ``NumericModel.evaluate`` state by state, on the
numpy backend and on the C backend, against a 50-digit solve of the same saddle-point
system (mpmath, from the float W, mu, F and drift): the worst error relative to the
largest acceleration there, and the solve the run reports. Then the model problem
x' + y' = 1, W = diag(1, b), a unit force on x, with x in metres, millimetres and
kilometres: the solve the decision chooses, and the relative error of x''.

Run it on two trees to compare (bench/RESULTS.md; ``NHHAM_TREE`` names the other)::

    python bench/kkt_units.py
    NHHAM_TREE=../before python bench/kkt_units.py
"""
from __future__ import annotations

import os
import signal
import sys
import warnings
from pathlib import Path

import mpmath
import numpy as np

ROOT = Path(os.environ.get("NHHAM_TREE", Path(__file__).resolve().parents[1])).resolve()
sys.path.insert(0, str(ROOT))

import nhham  # noqa: E402
from nhham.journeys.simulation import simulate  # noqa: E402
from nhham.numerics.kernels import columns  # noqa: E402
from nhham.numerics.nullspace import solve_null_space  # noqa: E402

SCENES = ["chaplygin_sleigh", "rolling_disk", "whipple_bicycle", "differential_drive_motors",
          "isokinetic_particle", "perpendicular_velocities", "disc_on_ground", "mass_ratio"]
mpmath.mp.dps = 50


def pieces(model, Y):
    n, m, k = model.n, model.m, model.k
    out = model.kernels.batch("saddle", Y, model.parameter_values)
    W, F, mu, drift, _, _ = columns(out, (n * n, n, m * n, m, m, k))
    K = Y.shape[0]
    return W.reshape(K, n, n), F, mu.reshape(K, m, n), drift


def exact(W, F, mu, drift):
    n, m = W.shape[0], mu.shape[0]
    K = mpmath.matrix(n + m, n + m)
    for i in range(n):
        for j in range(n):
            K[i, j] = W[i, j]
    for c in range(m):
        for j in range(n):
            K[n + c, j] = K[j, n + c] = mu[c, j]
    z = mpmath.lu_solve(K, mpmath.matrix([float(v) for v in F] + [float(-v) for v in drift]))
    return np.array([float(z[i]) for i in range(n)])


def scene_row(name):
    scene = nhham.load_scene(str(ROOT / "examples" / f"{name}.toml"))
    answer = simulate(scene, t_end=10.0)
    result = next(v for v in answer.payload.values() if hasattr(v, "model"))
    model = result.model
    Y = result.y.T if result.y.shape[0] == 2 * model.n else result.y
    W, F, mu, drift = pieces(model, Y)
    a = np.array([exact(W[i], F[i], mu[i], drift[i]) for i in range(Y.shape[0])])
    size = np.maximum(np.abs(a).max(axis=1), 1e-300)
    worst = {}
    for backend in ("numpy", "c"):   # the state by state solve and the compiled one
        evaluated = nhham.numeric_model(answer.system, backend=backend)
        dY = np.array([evaluated.evaluate(y)[0] for y in Y])
        worst[backend] = float((np.abs(dY[:, model.n:] - a).max(axis=1) / size).max())
    return name, Y.shape[0], result.kkt_solve, worst["numpy"], worst["c"]


def units_rows():
    rows = []
    for b in (1e2, 1e4, 1e6, 1e12):
        for unit, label in ((1.0, "m"), (1e-3, "mm"), (1e3, "km")):
            W = np.diag([unit ** 2, b])
            mu, top, bottom = np.array([[unit, 1.0]]), np.array([unit, 0.0]), np.zeros(1)
            x = solve_null_space(W, mu, top, bottom)[0]
            rel = abs(x[0] * unit * (1.0 + b) - 1.0)
            rows.append((b, label, rel, chosen(W)))
    return rows


def chosen(W):
    """The solve this tree takes (before issue 43's last change: by W's diagonal ratio)."""
    try:
        from nhham.numerics.nullspace import needs_null_space
    except ImportError:       # one solve everywhere
        return "null-space"
    return "null-space" if needs_null_space(W) else "saddle"


def main():
    warnings.simplefilter("ignore")

    def stop(*_):
        raise TimeoutError

    signal.signal(signal.SIGALRM, stop)
    print("| scene | states | solve | worst error / max |a|, numpy | C |\n|---|---|---|---|---|")
    for name in SCENES:
        signal.alarm(60)
        try:
            row = scene_row(name)
            print(f"| {row[0]} | {row[1]} | {row[2]} | {row[3]:.2g} | {row[4]:.2g} |",
                  flush=True)
        except TimeoutError:
            print(f"| {name} | over 60 s | | | |", flush=True)
        finally:
            signal.alarm(0)
    print("\n| b/a | x in | solve | relative error of x'' (numpy) |\n|---|---|---|---|")
    for b, label, rel, solve in units_rows():
        print(f"| {b:.0e} | {label} | {solve} | {rel:.2g} |")


if __name__ == "__main__":
    main()
