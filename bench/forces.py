"""What forces and inputs cost: each forced run beside its unforced baseline, one process.

* The snakeboard over one gait period (examples/snakeboard_gait.toml, DOP853 rtol 1e-10):
  the gait as expressions in t (compiled with the field, the C loop sets t) and as Python
  callables (the scipy loop sets the inputs at every evaluation), against the same
  integration of the unforced snakeboard from the same state with the same steps' budget;
* the bicycle's linearisation with B (examples/bicycle_steer_control.toml, two inputs)
  against the same without inputs (examples/whipple_bicycle.toml at v = 3);
* the controlled bicycle simulated for 1.5 s from a lean of 0.1 rad (the steer feedback
  compiled with the field) against the same bicycle with both torques zero over the same
  time (it weaves and falls over after about 1.6 s: a longer baseline would integrate the
  fall).

Models are built (and compiled) first; the table gives medians of ``--repeat`` runs of the
call a user makes after that, and the ratio to the baseline row measured in this process.

Run: ``python bench/forces.py [--repeat 7]``.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import nhham  # noqa: E402
from nhham.numerics.codegen import numeric_model  # noqa: E402
from nhham.numerics.linearization import linearize  # noqa: E402
from nhham.numerics.steady_sweep import with_steady_inputs  # noqa: E402
from nhham.system.scene import load_scene  # noqa: E402

EXAMPLES = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                        "examples")


def median(fn, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def snakeboard_rows(repeat):
    scene = load_scene(os.path.join(EXAMPLES, "snakeboard_gait.toml"))
    start = dict(scene.initial)
    closed = numeric_model(scene.system.closed_loop(scene.control))
    open_loop = numeric_model(scene.system)
    free = numeric_model(load_scene(os.path.join(EXAMPLES, "snakeboard.toml")).system)
    gait = {"u_psi": lambda t, y: 0.5 * math.sin(2 * math.pi * t),
            "u_phi": lambda t, y: 0.3 * math.cos(2 * math.pi * t)}
    free_start = dict(start, psi_dot=0.5)   # a moving board: the unforced one at rest stays
    opts = dict(rtol=1e-10, atol=1e-12, warn=False)
    return [
        ("snakeboard, no forces, 1 s (baseline)",
         median(lambda: nhham.simulate(free, (0, 1), free_start, **opts), repeat)),
        ("snakeboard, gait as expressions (compiled)",
         median(lambda: nhham.simulate(closed, (0, 1), start, **opts), repeat)),
        ("snakeboard, gait as Python callables",
         median(lambda: nhham.simulate(open_loop, (0, 1), start, controls=gait, **opts),
                repeat)),
    ]


def bicycle_rows(repeat):
    free_scene = load_scene(os.path.join(EXAMPLES, "whipple_bicycle.toml"))
    forced_scene = load_scene(os.path.join(EXAMPLES, "bicycle_steer_control.toml"))
    free = numeric_model(free_scene.system).with_parameters(v=3.0)
    forced = numeric_model(forced_scene.system)

    def lin(scene, model):
        m, state = with_steady_inputs(model, scene.steady.values(model.parameters))
        return linearize(m, state, family=scene.steady.family(m.parameters))

    closed = numeric_model(forced_scene.system.closed_loop(forced_scene.control))
    uncontrolled = numeric_model(forced_scene.system.closed_loop({"T_phi": "0",
                                                                  "T_delta": "0"}))
    start = dict(forced_scene.initial)
    opts = dict(rtol=1e-10, warn=False)
    return [
        ("bicycle linearize, no inputs (baseline)", median(lambda: lin(free_scene, free),
                                                           repeat)),
        ("bicycle linearize with B (2 inputs)", median(lambda: lin(forced_scene, forced),
                                                       repeat)),
        ("bicycle 1.5 s, torques 0 (baseline)",
         median(lambda: nhham.simulate(uncontrolled, (0, 1.5), start, **opts), repeat)),
        ("bicycle 1.5 s, steer feedback compiled",
         median(lambda: nhham.simulate(closed, (0, 1.5), start, **opts), repeat)),
    ]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    groups = [snakeboard_rows(args.repeat), bicycle_rows(args.repeat)]
    print(f"| run | median [ms] (of {args.repeat}) | ratio to its baseline |")
    print("|---|---|---|")
    for rows in groups:
        base = None
        for name, seconds in rows:
            if "(baseline)" in name:
                base = seconds
            ratio = "1" if base is None or seconds is base else f"{seconds / base:.2f}"
            print(f"| {name} | {1e3 * seconds:.3g} | {ratio} |")


if __name__ == "__main__":
    main()
