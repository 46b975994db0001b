"""Time each step for the models brought in from sympy.physics.mechanics.

Usage::

    python bench/mechanics.py [--classify-bound SECONDS]

For the Whipple bicycle, the 3-D rolling disc and the differential-drive robot:
build (the sympy.physics.mechanics model and ``from_mechanics``), load the
scene, generate the numeric model (codegen and C compile, on a fresh cache
directory), one linearisation about the [steady] motion, a sweep of 101
parameter values with its crossings, a 10 s simulation from [initial]
(DOP853, rtol 1e-10), and ``nhham classify`` in a subprocess stopped after the
bound (default 120 s). Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "examples"))

from nhham.journeys.stability import linearize  # noqa: E402
from nhham.numerics.codegen import numeric_model  # noqa: E402
from nhham.numerics.integrate import simulate  # noqa: E402
from nhham.system.scene import load_scene  # noqa: E402

MODELS = [("Whipple bicycle", "make_whipple_bicycle", "whipple_bicycle.toml", "v", (0, 10)),
          ("rolling disc 3-D", "make_rolling_disc_3d", "rolling_disc_3d.toml", "w", (0, 10)),
          ("differential drive", "make_differential_drive", "differential_drive.toml", "w",
           (-5, 5))]


def clock(f):
    t = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t


def classify_time(scene, bound):
    t = time.perf_counter()
    try:
        subprocess.run([sys.executable, "-m", "nhham", "classify", str(scene), "--json"],
                       cwd=ROOT, capture_output=True, timeout=bound, check=True)
    except subprocess.TimeoutExpired:
        return f"> {bound:.0f} s (stopped)"
    except subprocess.CalledProcessError as exc:
        return f"failed ({exc.returncode})"
    return f"{time.perf_counter() - t:.1f} s"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--classify-bound", type=float, default=120.0)
    args = ap.parse_args()
    print("| model | n, m | build | load scene | numeric model | linearize | sweep 101 | "
          "crossings | simulate 10 s | classify |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for label, module, scene_file, p, (lo, hi) in MODELS:
        mod = __import__(module)
        _, t_build = clock(mod.build)
        scene, t_load = clock(lambda: load_scene(ROOT / "examples" / scene_file))
        with tempfile.TemporaryDirectory() as cache:
            model, t_model = clock(lambda: numeric_model(scene.system, cache_dir=cache))
            _, t_lin = clock(lambda: linearize(scene, method="complex-step", model=model))
            swept, t_sweep = clock(lambda: linearize(
                scene, method="complex-step", sweep=(p, np.linspace(lo, hi, 101)), model=model))
            sw = swept.payload["sweep"]
            res, _ = clock(lambda: simulate(model, (0.0, 10.0), dict(scene.initial),
                                            method="DOP853", rtol=1e-10))
        cross = ", ".join(f"{c.kind} {p} = {c.value:.6f}" for c in sw.crossings) or "none"
        system = scene.system
        print(f"| {label} | {system.n}, {system.m} | {t_build:.2f} s | {t_load:.2f} s | "
              f"{t_model:.1f} s | {1e3 * t_lin:.0f} ms | {t_sweep:.2f} s | {cross} | "
              f"{1e3 * res.wall_time_s:.1f} ms ({res.nfev} evals) | "
              f"{classify_time(ROOT / 'examples' / scene_file, args.classify_bound)} |",
              flush=True)


if __name__ == "__main__":
    main()
