"""What parameter studies cost: the bicycle's stability map and an ensemble of snakes.

* ``map``: the self-stability map of the benchmark bicycle
  (examples/whipple_bicycle_benchmark.toml) over speed v = 0..10 m/s (201 values) and
  trail c = 0..0.2 m (101 values), linearised at every point with the weave and capsize
  boundaries located on every line, by :func:`nhham.sweep` with 1 worker (this process),
  2 worker processes and 2 threads. Each row gives the whole call (scene load, model,
  preparation, chunks, writing) and its chunks alone, their points per second and the
  parallel efficiency of the chunks (T1 / (2 T2)). Against, in the same process: the limit,
  numpy's eigenvalues of the benchmark's own 4 x 4 state matrices built from its
  closed-form M, C1, K0, K2 (Meijaard et al. 2007, Appendix A; tests/bicycle_benchmark.py)
  on the same grid in one batch; and the boundaries at the benchmark's trail against the
  paper's weave and capsize speeds. (A sympy user's route, ``Linearizer`` + ``lambdify`` +
  a loop: ``python bench/bicycle_user_route.py``.)
* ``ensemble``: the 8-link snake (examples/make_snake.py) from its [initial] state with
  the link rates perturbed (normal, sigma 0.05), ``--trajectories`` runs to t = 10 at
  rtol 1e-8 as one ``nhham.sweep(..., "simulate")`` with 1 and 2 workers, against the
  loop a user writes (``nhham.simulate`` per initial state, on the first 1000 of them),
  and the end states of 200 of them against single runs.

Medians of ``--repeat`` runs (the map; the ensemble runs once); ``large-map`` is the map
on 801 x 401 points. Run:
``python bench/sweep.py [map|large-map|ensemble|all] [--repeat 3] [--trajectories 100000]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.join(ROOT, "tests"))

import nhham  # noqa: E402
from bicycle_benchmark import BENCHMARK, benchmark_state_matrix  # noqa: E402

BICYCLE = os.path.join(ROOT, "examples", "whipple_bicycle_benchmark.toml")
OVER = ["v=0:10:201", "c=0:0.2:101"]
V_WEAVE, V_CAPSIZE = 4.2923825, 6.0242620


def _median(values):
    return statistics.median(values)


def bicycle_map(repeat, over=OVER):
    rows, results = [], {}
    nhham.sweep(BICYCLE, "linearize", ["v=4:5:3"], workers=1)   # imports and model, untimed
    for label, kwargs in (("nhham.sweep, 1 worker (this process)", dict(workers=1)),
                          ("nhham.sweep, 2 threads (the default)",
                           dict(workers=2, scheduler="threads")),
                          ("nhham.sweep, 2 worker processes",
                           dict(workers=2, scheduler="processes"))):
        walls, runs = [], []
        for _ in range(repeat):
            r = nhham.sweep(BICYCLE, "linearize", over, **kwargs)
            walls.append(r.wall_time_s)
            runs.append(r.run_time_s)
        results[label] = r
        rows.append((label, _median(walls), _median(runs), r.points))
    v = np.asarray(results[rows[0][0]].dataset["v"].values)
    c = np.asarray(results[rows[0][0]].dataset["c"].values)
    V, C = np.meshgrid(v, c, indexing="ij")
    limit = []
    for _ in range(max(repeat, 5)):
        start = time.perf_counter()
        A = benchmark_state_matrix(V, dict(BENCHMARK, c=C))
        np.linalg.eigvals(A)
        limit.append(time.perf_counter() - start)
    rows.append(("limit: numpy eig of the closed-form A(v, c)", _median(limit),
                 _median(limit), V.size))
    print(f"Bicycle stability map, {len(v)} x {len(c)} (v, trail): seconds (median of "
          f"{repeat}), points per second")
    print(f"  {'':48s} {'whole':>8s} {'chunks':>8s} {'pts/s (chunks)':>15s} {'vs limit':>9s}")
    for label, wall, run, n in rows:
        print(f"  {label:48s} {wall:8.3f} {run:8.3f} {n / run:15.0f} "
              f"{run / _median(limit):9.0f}")
    one = rows[0][2]
    for label, _, run, _ in rows[1:3]:
        print(f"  parallel efficiency of the chunks, {label[13:]}: {one / (2 * run):.2f}")
    ds = results[rows[0][0]].dataset
    j = list(ds["c"].values).index(0.08)
    kinds = list(ds["boundary_kind"].values[j])
    weave = ds["boundary"].values[j][kinds.index(1)]
    capsize = ds["boundary"].values[j][kinds.index(0)]
    print(f"  at c = 0.08: weave {weave:.9f} (paper {V_WEAVE}), capsize {capsize:.9f} "
          f"(paper {V_CAPSIZE}); differences {abs(weave - V_WEAVE):.1e}, "
          f"{abs(capsize - V_CAPSIZE):.1e}")
    same = all(np.array_equal(results[rows[0][0]].dataset[k].values,
                              results[label].dataset[k].values, equal_nan=True)
               for label in list(results)[1:] for k in ("eigenvalue_real", "boundary"))
    print(f"  the three schedulers give the same arrays: {same}")


def snake_ensemble(count):
    with tempfile.TemporaryDirectory() as tmp:
        scene = os.path.join(tmp, "snake_8.toml")
        subprocess.run([sys.executable, os.path.join(ROOT, "examples", "make_snake.py"), "8",
                        scene], check=True, capture_output=True)
        perturb = [f"theta{i}_dot=0.05" for i in range(1, 9)]
        opts = {"t_end": 10.0, "rtol": 1e-8, "atol": 1e-10}
        rows = []
        results = {}
        # the user's loop first (a fresh process: nothing held yet), on the first 1000
        # starts of the design, both ways a user calls simulate
        loop_n = min(1000, count)
        starts = nhham.sweep(scene, "simulate", [], samples_count=count,
                             initial_perturbation=perturb, seed=1,
                             run_options=dict(opts, t_end=1e-9), workers=1)
        y0 = starts.dataset["initial_state"].values
        loaded = nhham.load_scene(scene)
        model = nhham.numeric_model(loaded.system)
        loops = []
        for label, kw in (("loop of nhham.simulate", {}),
                          ("loop of nhham.simulate(t_eval=[10])", {"t_eval": [10.0]})):
            start = time.perf_counter()
            for i in range(loop_n):
                nhham.simulate(model, (0.0, 10.0), y0[i], rtol=1e-8, atol=1e-10, warn=False,
                               **kw)
            loop = time.perf_counter() - start
            loops.append((f"{label} ({loop_n} runs)", loop, loop, loop_n))
        for label, kwargs in (("nhham.sweep, 1 worker (this process)", dict(workers=1)),
                              ("nhham.sweep, 2 threads (the default)",
                               dict(workers=2, scheduler="threads")),
                              ("nhham.sweep, 2 worker processes",
                               dict(workers=2, scheduler="processes"))):
            r = nhham.sweep(scene, "simulate", [], samples_count=count,
                            initial_perturbation=perturb, seed=1, run_options=opts,
                            **kwargs)
            results[label] = r
            rows.append((label, r.wall_time_s, r.run_time_s, count))
        ds = results[rows[0][0]].dataset
        rows.extend(loops)
        rng = np.random.default_rng(0)
        worst = 0.0
        for i in rng.choice(count, size=min(200, count), replace=False):
            single = nhham.simulate(model, (0.0, 10.0), y0[i], rtol=1e-8, atol=1e-10,
                                    warn=False)
            worst = max(worst, float(np.max(np.abs(single.y[:, -1]
                                                   - ds["final_state"].values[i]))))
        print(f"8-link snake, {count} trajectories to t = 10 at rtol 1e-8: seconds, ms per "
              f"trajectory")
        print(f"  {'':48s} {'whole':>8s} {'chunks':>8s} {'ms/traj':>8s} {'vs loop':>8s}")
        per_loop = loops[0][1] / loop_n
        for label, wall, run, n in rows:
            print(f"  {label:48s} {wall:8.2f} {run:8.2f} {1e3 * run / n:8.3f} "
                  f"{(run / n) / per_loop:8.2f}")
        for label, _, run, _ in rows[1:3]:
            print(f"  parallel efficiency of the chunks, {label[13:]}: "
                  f"{rows[0][2] / (2 * run):.2f}")
        print(f"  end states against single runs (200 of them): max |difference| {worst:.1e}")
        same = all(np.array_equal(ds["final_state"].values,
                                  results[label].dataset["final_state"].values)
                   for label in list(results)[1:])
        print(f"  the three schedulers give the same arrays: {same}")
        print(f"  runs failed: {int((~ds['success'].values).sum())}; max |energy error| "
              f"{np.abs(ds['energy_error'].values).max():.1e}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("what", nargs="?", default="all",
                        choices=("map", "large-map", "ensemble", "all"))
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--trajectories", type=int, default=100_000)
    args = parser.parse_args()
    if args.what in ("map", "all"):
        bicycle_map(args.repeat)
    if args.what == "large-map":   # 16 times the points: the workers' start-up amortised
        bicycle_map(args.repeat, ["v=0:10:801", "c=0:0.2:401"])
    if args.what in ("ensemble", "all"):
        snake_ensemble(args.trajectories)


if __name__ == "__main__":
    main()
