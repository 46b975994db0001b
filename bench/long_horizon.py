"""Long horizons: the energy error and the constraint residual of each method against its
cost, at 10^2, 10^4 and 10^6 steps (issue 46).

Problems (the scenes of examples/ unless said):
  (a) contact_oscillator: McLachlan & Perlmutter's, reversible and integrable;
  (b) contact_oscillator_magnetic: the same with a gyroscopic term B (x y' - y x')/2,
      not reversible (L is not even in v), energy conserved;
  (c) the Chaplygin sleigh with m = I = a = 1 from u = 0, w = 1 (nhham.models), whose
      forward speed is sqrt(2) tanh(t/sqrt(2)) (by hand): the error of u at the end too;
  (d) nonholonomic_particle: Hamiltonizable (f = (1 + y^2)^(-1/2));
  (e) whipple_bicycle: the benchmark bicycle from its [initial] table (5 m/s, a roll rate
      of 0.5 rad/s: self-stable), no forces;
  (f) rubber_ball (Hamiltonizable after two reduction steps: --symmetry x,y --then yaw)
      with I2 = 0.14 (the largest moment: its pitch stays below 0.34 over 5000 s by
      DOP853) from pitch 0.2, roll 0.1, pitch' = 0.3, roll' = 2.

Each method runs N steps of h (h = 0.1, the bicycle 0.01; the adaptive DOP853 over the
same horizon N h at its default rtol 1e-9); states are kept every max(1, N/1000) steps.
Columns: the integration's wall time (``wall_time_s``: the model is built and compiled
before), the largest relative energy error |E - E0| / |E0| over the kept states, the
largest constraint residual, and the behaviour read from the errors: "rounding" (below
1e-12), "lost" (above 0.1), "bounded" (the largest error of the last quarter of the run at
most twice that of the second quarter, or 1e-12), "drift" otherwise, with the ratio (2 for
a linear growth, 4 for a quadratic one). A method that does not apply
says why. The Python loops (rk4, the Hamiltonized midpoint rule) skip 10^6 steps of the
bicycle.

Run::

    python bench/long_horizon.py                                  # 10^2 and 10^4 steps
    python bench/long_horizon.py --steps 100,10000,1000000 --plot docs/long_horizon.png
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import warnings

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import nhham  # noqa: E402
from nhham import models  # noqa: E402

METHODS = ("DOP853", "rk4", "rattle", "rattle4", "discrete_gradient", "hamiltonized")
PYTHON_LOOPS = ("rk4", "hamiltonized")


def _scene(name):
    scene = nhham.load_scene(os.path.join(ROOT, "examples", f"{name}.toml"))
    return scene.system, scene.checked_initial()


def _sleigh():
    system = models.chaplygin_sleigh(m=1.0, I=1.0, a=1.0)
    return system, dict(x=0.0, y=0.0, theta=0.0, x_dot=0.0, y_dot=1.0, theta_dot=1.0)


def _bicycle():
    system, start = _scene("whipple_bicycle")
    return system, start


def _rubber_ball():
    # I2 the largest moment (0.14 for 0.1): the roll about the body's y axis is stable and
    # the motion stays away from pitch = pi/2, the singularity of the z-x-y angles (with
    # the scene's I2 = 0.1 every fixed-step method stops there at t = 36.8)
    scene = nhham.load_scene(os.path.join(ROOT, "examples", "rubber_ball.toml"),
                             values={"I2": 0.14})
    system = scene.system
    start = dict(yaw=0.0, pitch=0.2, roll=0.1, x=0.0, y=0.0, pitch_dot=0.3, roll_dot=2.0)
    return system, start


PROBLEMS = {   # name: (what it is, (system, initial), h, the reduction of hamiltonized)
    "a contact oscillator": (lambda: _scene("contact_oscillator"), 0.1, {}),
    "b magnetic contact oscillator": (lambda: _scene("contact_oscillator_magnetic"), 0.1,
                                      {}),
    "c Chaplygin sleigh": (_sleigh, 0.1, {}),
    "d nonholonomic particle": (lambda: _scene("nonholonomic_particle"), 0.1, {}),
    "e Whipple bicycle": (_bicycle, 0.01, {}),
    "f rubber ball": (_rubber_ball, 0.05, {"symmetry": ["x", "y"], "then": ["yaw"]}),
}


def one_run(system, start, method, steps, h, reduced=None):
    """(seconds, max relative energy error, max residual, behaviour, run) or the reason."""
    options = {"save_every": max(1, steps // 1000), "warn": False}
    if method != "DOP853":
        options["step"] = h
    if method == "hamiltonized":
        options["reduced"] = reduced
    try:
        run = nhham.simulate(system, (0.0, steps * h), start, method=method, **options)
    except nhham.NhhamError as exc:
        return str(exc).split(";")[0]
    if not run.success:
        return f"stopped: {run.message}"
    E = run.energy
    err = np.abs(E - E[0]) / abs(E[0])
    res = float(run.constraint_residual_max)
    q = max(len(err) // 4, 1)
    late, middle = float(np.max(err[-q:])), float(np.max(err[q:2 * q] if len(err) > 2 * q
                                                         else err[:q]))
    if np.max(err) < 1e-12:
        kind = "rounding"
    elif np.max(err) > 0.1:
        kind = "lost (of order 1)"
    elif late <= 2 * max(middle, 1e-12):
        kind = "bounded"
    else:
        kind = f"drift x{late / max(middle, 1e-12):.3g}"
    return run.wall_time_s, float(np.max(err)), res, kind, run


def rows_from(path):
    """The rows of a table this script printed (to draw it again without running)."""
    rows = []
    for line in open(path):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 8:
            try:
                rows.append((cells[0], cells[1], int(cells[2]), float(cells[4]),
                             float(cells[5]), float(cells[6])))
            except ValueError:
                continue
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--problems", default="a,b,c,d,e,f",
                        help="letters of the problems (default all)")
    parser.add_argument("--methods", default=",".join(METHODS))
    parser.add_argument("--steps", default="100,10000")
    parser.add_argument("--plot", default=None, help="write the figure (matplotlib)")
    parser.add_argument("--from-table", default=None, metavar="FILE",
                        help="draw the figure from a table this script printed, no runs")
    args = parser.parse_args(argv)
    if args.from_table:
        _plot(rows_from(args.from_table), args.plot)
        return
    wanted = set(args.problems.split(","))
    counts = [int(float(s)) for s in args.steps.split(",")]
    rows = []
    print("| problem | method | steps | h | wall s | max rel. energy error | max residual "
          "| energy error |\n|---|---|---|---|---|---|---|---|", flush=True)
    warnings.simplefilter("ignore")
    for name, (make, h, reduction) in PROBLEMS.items():
        if name[0] not in wanted:
            continue
        system, start = make()
        nhham.numeric_model(system, backend="c")   # compiled now: the runs time the loops
        reduced = None
        for method in args.methods.split(","):
            if method == "hamiltonized":
                from nhham.journeys.hamiltonized_motion import hamiltonized_field

                try:
                    reduced = hamiltonized_field(system, **reduction)[0]
                except nhham.NhhamError as exc:
                    print(f"| {name} | {method} | | | does not apply: "
                          f"{str(exc).split(';')[0]} | | | |", flush=True)
                    continue
            for steps in counts:
                if name[0] == "e" and method in PYTHON_LOOPS and steps > 10 ** 5:
                    print(f"| {name} | {method} | {steps} | {h} | skipped: a Python loop "
                          f"(hours) | | | |", flush=True)
                    continue
                row = one_run(system, start, method, steps, h, reduced)
                if isinstance(row, str):
                    said = row if row.startswith("stopped") else f"does not apply: {row}"
                    print(f"| {name} | {method} | {steps} | {h} | {said} | | | |", flush=True)
                    break
                wall, err, res, kind, run = row
                extra = ""
                if name[0] == "c":   # the closed form of the forward speed
                    th, xd, yd = run["theta"][-1], run["x_dot"][-1], run["y_dot"][-1]
                    u = math.cos(th) * xd + math.sin(th) * yd
                    t = run.t[-1]
                    extra = f" (u off by {abs(u - math.sqrt(2) * math.tanh(t / math.sqrt(2))):.1e})"
                print(f"| {name} | {method} | {steps} | {h} | {wall:.3g} | {err:.2e} | "
                      f"{res:.2e} | {kind}{extra} |", flush=True)
                rows.append((name, method, steps, wall, err, res))
    if args.plot:
        _plot(rows, args.plot)


def _plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(r[0] for r in rows))
    cols = min(3, len(names))
    nrows = -(-len(names) // cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.2 * cols, 3.4 * nrows), squeeze=False)
    markers = dict(zip(METHODS, "osD^vP"))
    colours = dict(zip(METHODS, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    for ax in axes.flat[len(names):]:
        ax.set_visible(False)
    for ax, name in zip(axes.flat, names):
        for method in METHODS:   # one colour and marker per method in every panel
            mine = [r for r in rows if r[0] == name and r[1] == method]
            if not mine:
                continue
            ax.loglog([max(r[3], 1e-5) for r in mine], [max(r[4], 1e-17) for r in mine],
                      marker=markers[method], color=colours[method], label=method)
            for r in mine:
                ax.annotate(f"1e{round(math.log10(r[2]))}", (max(r[3], 1e-5), max(r[4], 1e-17)),
                            fontsize=6, xytext=(2, 2), textcoords="offset points")
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("wall time of the integration (s)")
        ax.grid(True, which="major", alpha=0.3)
    for row in axes:
        row[0].set_ylabel("max |E - E0| / |E0|")
    handles = {}
    for ax in axes.flat:
        for line in ax.get_lines():
            handles.setdefault(line.get_label(), line)
    fig.legend(list(handles.values()), list(handles), loc="lower center",
               ncol=len(handles), fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    fig.savefig(path, dpi=110)
    print(f"\nfigure: {path}")


if __name__ == "__main__":
    main()
