"""Long horizons: the energy error and the constraint residual of each method against its
cost, at 10^2, 10^4 and 10^6 steps of h (issue 46).

For each scene and each method: one run of N steps of h = 0.1 (the fixed-step methods) or
over the same horizon N h (the adaptive ones, at their default tolerances, projected), the
states kept every max(1, N/1000) steps; the integration's wall time (``wall_time_s``: the
model is built before it, the compiled library from the cache); the largest relative energy error
|E - E0 - work| / |E0| over the kept states (work: the reactions' work where the
constraints are affine and the method carries it; the energy balance of the run
otherwise) and the largest constraint residual, the CPU time and the error's growth
between the first and the second half of the run (``trend``: the ratio of their maxima;
about 1 for a bounded error, 2 or more for a drift).

Run::

    python bench/long_horizon.py                       # every scene, 10^2 and 10^4 steps
    python bench/long_horizon.py --steps 1000000 --scenes contact_oscillator \\
        --methods discrete_gradient

Scenes (examples/): contact_oscillator (reversible, integrable), contact_oscillator_magnetic
(a gyroscopic term: not reversible), chaplygin_sleigh, whipple_bicycle.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import nhham  # noqa: E402
from nhham.journeys.simulation import simulate  # noqa: E402

SCENES = ("contact_oscillator", "contact_oscillator_magnetic", "chaplygin_sleigh",
          "whipple_bicycle")
METHODS = ("discrete_gradient", "rattle", "rattle4", "rk4", "DOP853")
H = 0.1


def one_run(name, method, steps, h=H):
    """(seconds, max relative energy error, max residual, trend) or the reason."""
    scene = nhham.load_scene(os.path.join(ROOT, "examples", f"{name}.toml"))
    options = {"method": method, "save_every": max(1, steps // 1000)}
    if method in ("discrete_gradient", "rattle", "rattle4", "rk4"):
        options["step"] = h
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            answer = simulate(scene, t_end=steps * h, options=options)
        except nhham.NhhamError as exc:
            return str(exc).split(";")[0]
    result = next(v for v in answer.payload.values() if hasattr(v, "model"))
    cpu = result.wall_time_s    # the integration's own time (the model is built before)
    Y = result.y.T if result.y.shape[0] == 2 * result.model.n else result.y
    E = result.model.energy(Y)
    work = result.work if getattr(result, "work", None) is not None else np.zeros(len(E))
    err = np.abs(E - E[0] - work) / abs(E[0])
    res = float(np.max(np.abs(result.model.residuals(Y))))
    half = len(err) // 2
    trend = float(np.max(err[half:]) / max(np.max(err[:half]), 1e-300)) if half else 1.0
    return cpu, float(np.max(err)), res, trend


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default=",".join(SCENES))
    parser.add_argument("--methods", default=",".join(METHODS))
    parser.add_argument("--steps", default="100,10000")
    args = parser.parse_args(argv)
    print("| scene | method | steps of 0.1 | integration s | max rel. energy error | max residual "
          "| trend |\n|---|---|---|---|---|---|---|", flush=True)
    for name in args.scenes.split(","):
        for method in args.methods.split(","):
            for steps in (int(float(s)) for s in args.steps.split(",")):
                row = one_run(name, method, steps)
                if isinstance(row, str):
                    print(f"| {name} | {method} | {steps} | refused: {row} | | | |", flush=True)
                    break
                cpu, err, res, trend = row
                print(f"| {name} | {method} | {steps} | {cpu:.3g} | {err:.2e} | {res:.2e} "
                      f"| {trend:.2g} |", flush=True)


if __name__ == "__main__":
    main()
