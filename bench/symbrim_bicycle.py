"""SymBRiM's Whipple bicycle linearised by nhham, without a scene file.

What a SymBRiM user does to get the benchmark eigenvalues of Meijaard et al. (2007) from
the model SymBRiM builds, with nhham doing the linearisation:

* model: SymBRiM's ``WhippleBicycle`` (Moore's convention, SymBRiM's default: flat
  ground, rigid rear and front frames, knife-edge wheels, non-holonomic tires), as its
  tutorial builds it, exported with ``to_system()`` (a
  ``sympy.physics.mechanics.System``: coordinates q1..q8, speeds u1..u8 with
  u_i = q_i', the front contact's holonomic constraint and four rolling constraints),
  gravity ``apply_uniform_gravity(-g * normal)``;
* parameters: SymBRiM's own ``get_param_values`` with a ``bicycleparameters.Bicycle``
  (the ``Benchmark`` set bundled with bicycleparameters). SymBRiM converts Meijaard's
  parameters to Moore's with ``dtk.bicycle.benchmark_to_moore``: the rear and front
  offsets d1, d3 and the steer-axis length d2 from w, c, lambda, rR, rF; the mass
  centres l1, l2 (rear frame, from the rear wheel centre) and l3, l4 (front frame, from
  the front wheel centre) in frames pitched by the steer-axis tilt lambda; the frame
  and fork inertias rotated by lambda (I' = R_y(lambda) I R_y(lambda)^T); masses and
  wheel inertias as they are; g a Symbol of ours. The file bicycleparameters bundles
  rounds the fork's inertia (IHxx 0.0589, IHzz 0.0071, IHxz -0.0076 for Table 1's
  0.05892, 0.00708, -0.00756), so by default its values are replaced by Table 1's
  (``tests/bicycle_benchmark.py``) before SymBRiM reads them; ``--bundled`` keeps the
  file's (the closed form is then evaluated at the file's values too);
* nhham: ``from_mechanics(system, parameters=values)`` (SymBRiM's Symbols as keys),
  then ``linearize(bike, steady={...}, model=numeric_model(bike, backend="numpy"))``
  with the steady motion in SymBRiM's own dynamicsymbols and speeds: q1..q4, q6..q8 = 0
  (pitch q5 solved from the holonomic constraint: lambda), lean rate u4 = 0, steer
  rate u7 = 0 and rear wheel rate u6 = -v / rR (``bike.rear_wheel.radius``: in Moore's
  convention z points down and the wheel axis along y to the right, so forward riding
  turns the rear wheel negatively, as SymBRiM's tutorial sets it); the other speeds
  are solved from the constraints;
* check: the eigenvalues nhham reports (the neutral directions x, y, yaw, wheel angles
  and the speed removed: the lean/steer block) against the closed form of
  ``tests/bicycle_benchmark.py`` (the paper's Appendix A) at each v, paired by
  assignment; at v = 0 and 5 also against Table 2 of the paper.

Usage::

    python bench/symbrim_bicycle.py                # v = 0..10, 11 speeds, numpy kernels
    python bench/symbrim_bicycle.py --bundled      # bicycleparameters' rounded file
    python bench/symbrim_bicycle.py --backend auto # nhham's default (C when it compiles)
    python bench/symbrim_bicycle.py --sweep 101    # also linearize(..., sweep=("v", ...))

``--sweep N`` adds a Symbol v to the parameters (value 5), writes the rear wheel's rate
u6 = -v/rR (v enters no expression of the model: with ``--backend auto`` its numeric model
finds the library of the model without v), and lets ``linearize(..., sweep=("v", linspace(0, 10, N)))`` find where an
eigenvalue crosses the imaginary axis (the weave and capsize speeds, against the paper's
4.29238253634111 and 6.02426201538837); the other entries are solved again at each v.

Exits 2 with one line naming the package when symbrim or bicycleparameters is missing.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import os
import statistics
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

#: Meijaard et al. (2007), section 5: the weave and capsize speeds of the benchmark.
WEAVE, CAPSIZE = 4.29238253634111, 6.02426201538837

#: Table 2 of Meijaard et al. (2007): the eigenvalues at v = 0 and v = 5 m/s.
TABLE_2 = {
    0.0: (3.13164324790656, -3.13164324790656, 5.53094371765393, -5.53094371765393),
    5.0: (-14.0783896927982, -0.775341882195845 + 4.46486771378823j,
          -0.775341882195845 - 4.46486771378823j, -0.322866429004087),
}


def require(*names):
    """The modules ``names``, or exit 2 naming the first that is missing."""
    out = []
    for name in names:
        try:
            out.append(importlib.import_module(name))
        except ImportError:
            print(f"symbrim_bicycle.py: needs the package {name} "
                  f"(pip install symbrim bicycleparameters)", file=sys.stderr)
            raise SystemExit(2) from None
    return out


def clock(f):
    """(f(), (wall seconds, CPU seconds of this process))."""
    t0, c0 = time.perf_counter(), time.process_time()
    out = f()
    return out, (time.perf_counter() - t0, time.process_time() - c0)


def symbrim_bicycle(sb, sp):
    """(SymBRiM's WhippleBicycle, its sympy.physics.mechanics System, g)."""
    bike = sb.WhippleBicycle("bike")
    bike.ground = sb.FlatGround("ground")
    bike.rear_frame = sb.RigidRearFrame("rear_frame")
    bike.front_frame = sb.RigidFrontFrame("front_frame")
    bike.rear_wheel = sb.KnifeEdgeWheel("rear_wheel")
    bike.front_wheel = sb.KnifeEdgeWheel("front_wheel")
    bike.rear_tire = sb.NonHolonomicTire("rear_tire")
    bike.front_tire = sb.NonHolonomicTire("front_tire")
    bike.define_all()
    system = bike.to_system()
    g = sp.Symbol("g")
    system.apply_uniform_gravity(-g * bike.ground.get_normal(bike.ground.origin))
    return bike, system, g


def benchmark_values(bp, bike, g, bundled):
    """(SymBRiM's parameter values {Symbol: float}, Meijaard's parameters used)."""
    from bicycleparameters.io import remove_uncertainties
    from bicycle_benchmark import BENCHMARK

    data = os.path.join(os.path.dirname(bp.__file__), "app-data")
    with contextlib.redirect_stdout(io.StringIO()):   # its note on parameters found
        bicycle = bp.Bicycle("Benchmark", pathToData=data)
    if not bundled:
        bicycle.parameters["Benchmark"] = dict(BENCHMARK)
    meijaard = {k: float(v) for k, v in
                remove_uncertainties(bicycle.parameters["Benchmark"]).items()}
    values = bike.get_param_values(bicycle)
    values[g] = meijaard["g"]
    return values, meijaard


def pairing_difference(got, want):
    """Largest |got - want| with the eigenvalues paired by assignment."""
    import numpy as np
    from scipy.optimize import linear_sum_assignment

    d = np.abs(np.asarray(got)[:, None] - np.asarray(want)[None, :])
    r, c = linear_sum_assignment(d)
    return float(d[r, c].max()) if len(got) == len(want) else float("inf")


def nonzero(pairs):
    """The nonzero eigenvalues of a linearize answer's ``[re, im]`` pairs."""
    import numpy as np

    z = np.array([complex(re, im) for re, im in pairs])
    return z[np.abs(z) > 1e-9]


def fmt(z) -> str:
    return f"{z.real:.9f}" if z.imag == 0 else f"{z.real:.9f}{z.imag:+.9f}i"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speeds", type=int, default=11, help="how many v in [0, 10]")
    ap.add_argument("--bundled", action="store_true",
                    help="bicycleparameters' Benchmark file as it is (rounded fork inertia)")
    ap.add_argument("--backend", choices=("numpy", "auto"), default="numpy",
                    help="the numeric model's kernels (auto: C when a compiler works)")
    ap.add_argument("--sweep", type=int, default=0, metavar="N",
                    help="also sweep v over N values in [0, 10] (v a parameter)")
    args = ap.parse_args()
    t_all, c_all = time.perf_counter(), time.process_time()
    sb, bp = require("symbrim", "bicycleparameters")
    import numpy as np
    import sympy as sp

    import nhham
    from bicycle_benchmark import benchmark_state_matrix

    warnings.filterwarnings("ignore", category=UserWarning)  # uncertainties, sympy paths
    times = {}
    (bike, system, g), times["SymBRiM: define_all, to_system, gravity"] = clock(
        lambda: symbrim_bicycle(sb, sp))
    (values, meijaard), times["parameters: get_param_values (Meijaard -> Moore)"] = clock(
        lambda: benchmark_values(bp, bike, g, args.bundled))
    model_bike, times["nhham.from_mechanics"] = clock(
        lambda: nhham.from_mechanics(system, parameters=values))
    model, times[f"nhham.numeric_model (backend={args.backend})"] = clock(
        lambda: nhham.numeric_model(model_bike, backend=args.backend))

    q, u = bike.q, bike.u
    rR = bike.rear_wheel.radius          # a SymBRiM Symbol: the steady table's expression

    def steady(v, forward=True):
        table = {qi: 0 for i, qi in enumerate(q) if i != 4}   # q5 (pitch) solved
        table.update({u[3]: 0, u[6]: 0, u[5]: (-v if forward else v) / rR})
        return table

    speeds = np.linspace(0.0, 10.0, args.speeds)
    rows, calls = [], []
    worst = 0.0
    for v in speeds:
        answer, dt = clock(lambda: nhham.linearize(model_bike, steady=steady(float(v)),
                                                   model=model))
        calls.append(dt)
        got = nonzero(answer.data["eigenvalues"])
        want = np.linalg.eigvals(benchmark_state_matrix(float(v), meijaard))
        diff = pairing_difference(got, want)
        worst = max(worst, diff)
        table2 = TABLE_2.get(float(v))
        rows.append((v, np.sort_complex(got), np.sort_complex(want), diff,
                     None if table2 is None else pairing_difference(got, table2)))

    chart = answer.data["chart"]
    # the sign of u6: +v/rR rides backward, the benchmark at -v
    back = nhham.linearize(model_bike, steady=steady(5.0, forward=False), model=model)
    back_got = nonzero(back.data["eigenvalues"])
    back_diff, back_fwd = (pairing_difference(back_got, np.linalg.eigvals(
        benchmark_state_matrix(speed, meijaard))) for speed in (-5.0, 5.0))
    print(f"SymBRiM Whipple bicycle (Moore): {len(model_bike.coordinates)} coordinates, "
          f"{len(model_bike.phi)} velocity constraints (1 holonomic), "
          f"{len(model_bike.parameters)} parameters ("
          + ("bicycleparameters' bundled Benchmark file" if args.bundled
             else "Meijaard's Table 1") + ")")
    print(f"chart of the last linearisation: {chart}")
    print()
    print("| v (m/s) | nhham: eigenvalues of the lean/steer block | closed form (Appendix A) "
          "| max diff | vs Table 2 |")
    print("|---|---|---|---|---|")
    for v, got, want, diff, t2 in rows:
        print(f"| {v:g} | {', '.join(fmt(z) for z in got)} | "
              f"{', '.join(fmt(z) for z in want)} | {diff:.1e} | "
              f"{'' if t2 is None else f'{t2:.1e}'} |")
    print()
    print(f"u6 = +v/rR at v = 5 (riding backward): "
          f"{', '.join(fmt(z) for z in np.sort_complex(back_got))}; "
          f"max diff {back_diff:.1e} from the closed form at v = -5, "
          f"{back_fwd:.1e} from that at v = +5")
    print()
    print("| step | wall | CPU |")
    print("|---|---|---|")
    for label, (wall, cpu) in times.items():
        print(f"| {label} | {wall:.2f} s | {cpu:.2f} s |")
    print(f"| nhham.linearize, first call (v = {speeds[0]:g}) | {calls[0][0]:.2f} s | "
          f"{calls[0][1]:.2f} s |")
    if len(calls) > 1:
        later = [sorted(c[k] for c in calls[1:]) for k in (0, 1)]
        print(f"| nhham.linearize, later calls (median of {len(calls) - 1}; min-max) | "
              + " | ".join(f"{statistics.median(x):.2f} s ({x[0]:.2f}-{x[-1]:.2f})"
                           for x in later) + " |")
    print(f"| main so far (imports of symbrim, nhham... included) | "
          f"{time.perf_counter() - t_all:.1f} s | {time.process_time() - c_all:.1f} s |")
    print(f"largest eigenvalue difference vs the closed form, all {len(rows)} speeds: "
          f"{worst:.1e}")
    if args.sweep:
        sweep_speed(nhham, sp, np, system, values, bike, args, model)


def sweep_speed(nhham, sp, np, system, values, bike, args, first):
    """``linearize(..., sweep=("v", ...))`` with v a parameter: the crossings. v enters no
    expression of the model: with C, the model of ``first`` (without v) has its library."""
    v = sp.Symbol("v")
    swept_bike, (wall, cpu) = clock(
        lambda: nhham.from_mechanics(system, parameters={**values, v: 5.0}))
    model, (m_wall, m_cpu) = clock(lambda: nhham.numeric_model(swept_bike,
                                                               backend=args.backend))
    q, u = bike.q, bike.u
    steady = {qi: 0 for i, qi in enumerate(q) if i != 4}
    steady.update({u[3]: 0, u[6]: 0, u[5]: -v / bike.rear_wheel.radius})
    grid = np.linspace(0.0, 10.0, args.sweep)
    answer, (s_wall, s_cpu) = clock(lambda: nhham.linearize(
        swept_bike, steady=steady, model=model, sweep=("v", grid)))
    swept = answer.payload["sweep"]
    print()
    print(f"linearize(..., sweep=('v', {args.sweep} values in [0, 10])): "
          f"{s_wall:.2f} s wall, {s_cpu:.2f} s CPU (before it, from_mechanics with v: "
          f"{wall:.2f} s wall, {cpu:.2f} s CPU; numeric_model: {m_wall:.2f} s, {m_cpu:.2f} s); "
          f"stable at {sum(1 for s in swept.stable if s)} of {len(grid)}")
    if model.compiled is not None and first.compiled is not None:
        same = model.compiled.path == first.compiled.path
        print(f"the model with v on the library of the model without it: {same}")
    for c, paper in zip(swept.crossings, (WEAVE, CAPSIZE)):
        print(f"  crossing at v = {c.value:.11f} ({c.kind}); paper {paper:.11f}, "
              f"difference {abs(c.value - paper):.1e}")


if __name__ == "__main__":
    main()
