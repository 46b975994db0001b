"""The user's route to the bicycle's stability map: sympy's Linearizer, lambdify, numpy.

What a sympy.physics.mechanics user does today to get the eigenvalues of the Whipple
bicycle over forward speed v and trail c, the baseline nhham's sweep is compared with.
Only sympy, numpy and scipy do the work (the model comes from
``examples/make_whipple_bicycle.py``, whose import also loads nhham; nothing of nhham is
called):

* model: ``mechanics_model()`` of ``examples/make_whipple_bicycle.py`` (sympy's
  test_kane3 frames and parameterisation, q' = u, front contact on the ground as the
  holonomic constraint, four rolling constraints, gravity), re-declared as a
  ``sympy.physics.mechanics.System`` with pitch the dependent coordinate and the lean,
  rear-wheel and steer rates (u4, u6, u7) the independent speeds;
* equations: ``System.form_eoms(constraint_solver="CRAMER")`` (KanesMethod);
* linearisation: ``to_linearizer(linear_solver="CRAMER")`` and ``linearize(op_point,
  A_and_B=False)`` about the upright steady motion q = 0, x' = v, thetaR' = v/rR,
  thetaF' = v/rF, u' = 0, with v and all 27 parameters symbolic. The explicit form
  ``A_and_B=True`` (sympy's own test_kane3 route) does not finish here: see
  ``--explicit-bound``. The ``LU`` solvers give nan (0/0 at the operating point);
* lambdify (numpy) the implicit M (16 x 16) and A (16 x 10) of M [q', u'] = A [q_i, u_i];
  at each grid point the state matrix is P^T M^-1 A (``np.linalg.solve``, as the
  Linearizer docstring suggests for many symbolic parameters), reduced to the benchmark's
  4 x 4 block in (phi, delta, phi', delta') (the dropped states x, y, psi, thetaR, thetaF
  and the rear-wheel rate enter none of those four rows: checked), then
  ``np.linalg.eigvals``;
* the grid v = 0..10 (201 values) x c = 0..0.2 (101 values) in a plain Python loop,
  timed (median of ``--runs`` repetitions of the whole loop), and checked against the
  closed form of ``tests/bicycle_benchmark.py`` (paper, Appendix A) at every point.

The trail c enters through the conversion of ``benchmark_parameters()`` (copied here as
:func:`trail_parameters`): forkoffset, framelength and forkcg3 change with c.

Usage::

    python bench/bicycle_user_route.py                         # full grid, 3 runs
    python bench/bicycle_user_route.py --explicit-bound 900    # also try A_and_B=True

``--explicit-bound S`` also runs ``linearize(op_point, A_and_B=True, linear_solver=
"CRAMER")`` in two child processes (in parallel, after the timings above), stopped after
S seconds of linearisation: all parameters symbolic, and all but v and the three
trail-dependent ones substituted into the Linearizer's equations before its setup.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing as mp
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import sympy as sp
from scipy.optimize import linear_sum_assignment
from sympy.physics import mechanics as me

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "tests"))

from make_whipple_bicycle import _PAPER, benchmark_parameters, mechanics_model  # noqa: E402
from bicycle_benchmark import BENCHMARK, benchmark_state_matrix  # noqa: E402

# sympy warns that some mass centres' velocities could be found along several paths of
# points; every point is located from O, so all paths give the same velocity.
warnings.filterwarnings("ignore", message="\\s*Velocity of", category=UserWarning)

V_GRID = np.linspace(0.0, 10.0, 201)
C_GRID = np.linspace(0.0, 0.2, 101)
TRAIL_DEPENDENT = ("forkoffset", "framelength", "forkcg3")
PARAMETERS = tuple(benchmark_parameters())  # the 27 parameter names of the model
v = sp.Symbol("v")


def trail_parameters(c: float) -> dict:
    """The model's parameter values for trail ``c`` (everything else as in the paper):
    the conversion of ``benchmark_parameters()`` with ``trail = c``."""
    p = {k: float(x) for k, x in _PAPER.items()}
    HTA = math.pi / 2 - p["lam"]
    rake = -(c * math.sin(HTA) - p["rF"] * math.cos(HTA))
    framelength = p["wheelbase"] * math.sin(HTA) - (rake - (p["rF"] - p["rR"]) * math.cos(HTA))
    ta = p["zH"] - p["rF"]
    tb = p["wheelbase"] - p["xH"]
    tc = math.sqrt(ta ** 2 + tb ** 2)
    forkcg_norm = rake + tc * math.sin(math.pi / 2 - HTA - math.acos(ta / tc))
    values = benchmark_parameters()
    values.update(forkoffset=rake, framelength=framelength, forkcg3=forkcg_norm)
    return values


def kane_system():
    """(System with pitch dependent and u4, u6, u7 independent, q, u)."""
    src, _ = mechanics_model()
    q, u = list(src.q), list(src.u)
    names = [s.name for s in q]
    ip = names.index("pitch")
    ind = [names.index("phi"), names.index("thetaR"), names.index("delta")]
    system = me.System(src.frame, src.fixed_point)
    system.add_coordinates(*[qi for i, qi in enumerate(q) if i != ip])
    system.add_coordinates(q[ip], independent=False)
    system.add_speeds(*[u[i] for i in ind])
    system.add_speeds(*[ui for i, ui in enumerate(u) if i not in ind], independent=False)
    system.add_kdes(*src.kdes)
    system.add_bodies(*src.bodies)
    system.add_loads(*src.loads)
    system.add_holonomic_constraints(*src.holonomic_constraints)
    system.add_nonholonomic_constraints(*src.nonholonomic_constraints)
    return system, q, u


def operating_point(q, u, rR, rF) -> dict:
    """Upright straight-ahead motion at speed v (this model: x' = v, thetaR' = v/rR,
    thetaF' = v/rF, everything else and all accelerations zero)."""
    t = me.dynamicsymbols._t
    names = [s.name for s in q]
    op = {qi: 0 for qi in q}
    op.update({ui: 0 for ui in u})
    op.update({ui.diff(t): 0 for ui in u})
    op[u[names.index("x")]] = v
    op[u[names.index("thetaR")]] = v / rR
    op[u[names.index("thetaF")]] = v / rF
    return op


def clock(f):
    t0 = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t0


def setup():
    """Model, equations, implicit linearisation, lambdify: (functions, indices, times)."""
    times = {}
    (system, q, u), times["model (mechanics_model + System)"] = clock(kane_system)
    _, times["form_eoms (KanesMethod, CRAMER)"] = clock(
        lambda: system.form_eoms(constraint_solver="CRAMER"))
    lin, t_to = clock(lambda: system.eom_method.to_linearizer(linear_solver="CRAMER"))
    op = operating_point(q, u, sp.Symbol("rR"), sp.Symbol("rF"))
    (M, A, _), t_lin = clock(lambda: lin.linearize(op_point=op, A_and_B=False))
    times["linearize (A_and_B=False)"] = t_to + t_lin
    state = [s.name for s in (*lin.q_i, *lin.u_i)]
    idx = [state.index(n) for n in ("phi", "delta", "u4", "u7")]  # u4 = phi', u7 = delta'
    args = [v, *sp.symbols(PARAMETERS)]
    loose = (M.free_symbols | A.free_symbols) - set(args)
    assert not loose, loose
    (fM, fA), times["lambdify M, A (numpy)"] = clock(
        lambda: (sp.lambdify(args, M, "numpy"), sp.lambdify(args, A, "numpy")))
    PT = np.array(lin.perm_mat.T, dtype=float)
    return fM, fA, PT, idx, times, (M.shape, A.shape, state)


def state_matrix(fM, fA, PT, speed, p):
    """The full 10 x 10 state matrix P^T M^-1 A in (q_i, u_i) at one point."""
    return PT @ np.linalg.solve(fM(speed, *p), fA(speed, *p))


def sweep(fM, fA, PT, idx, vs, cs):
    """Eigenvalues of the 4 x 4 lean/steer block over the grid, plain loops."""
    out = np.empty((len(cs), len(vs), 4), dtype=complex)
    block = np.ix_(idx, idx)
    for i, c in enumerate(cs):
        values = trail_parameters(c)
        p = [values[k] for k in PARAMETERS]
        for j, speed in enumerate(vs):
            out[i, j] = np.linalg.eigvals(state_matrix(fM, fA, PT, speed, p)[block])
    return out


def max_difference(ev, reference):
    """Largest |lambda - lambda_ref| over all points, eigenvalues paired by assignment."""
    worst, where = 0.0, None
    for index in np.ndindex(ev.shape[:-1]):
        d = np.abs(ev[index][:, None] - reference[index][None, :])
        r, c = linear_sum_assignment(d)
        m = d[r, c].max()
        if m > worst:
            worst, where = m, index
    return worst, where


def explicit_child(variant, queue):
    """``linearize(A_and_B=True)`` as sympy's test_kane3 does it; phases to ``queue``."""
    warnings.filterwarnings("ignore", message="\\s*Velocity of", category=UserWarning)
    system, q, u = kane_system()
    system.form_eoms(constraint_solver="CRAMER")
    queue.put(("start", time.perf_counter()))
    lin = system.eom_method.to_linearizer(linear_solver="CRAMER")
    values = benchmark_parameters()
    if variant == "numeric":
        num = {sp.Symbol(k): sp.Float(x) for k, x in values.items() if k not in TRAIL_DEPENDENT}
        for name in ("f_0", "f_1", "f_2", "f_3", "f_4", "f_c", "f_v", "f_a"):
            setattr(lin, name, getattr(lin, name).xreplace(num))
        op = operating_point(q, u, values["rR"], values["rF"])
    else:
        op = operating_point(q, u, sp.Symbol("rR"), sp.Symbol("rF"))
    lin._setup()
    queue.put(("setup", time.perf_counter()))
    lin.linearize(op_point=op, A_and_B=True)
    queue.put(("done", time.perf_counter()))


def explicit_attempts(bound):
    """Run both A_and_B=True variants in parallel child processes, bounded."""
    ctx = mp.get_context("fork")
    runs = {}
    for variant in ("symbolic", "numeric"):
        queue = ctx.Queue()
        proc = ctx.Process(target=explicit_child, args=(variant, queue), daemon=True)
        proc.start()
        runs[variant] = (proc, queue, {})
    deadline = None
    while True:
        for proc, queue, seen in runs.values():
            while not queue.empty():
                phase, stamp = queue.get()
                seen[phase] = stamp
        starts = [seen.get("start") for _, _, seen in runs.values()]
        if deadline is None and all(starts):
            deadline = time.perf_counter() + bound
        alive = [p for p, _, seen in runs.values() if "done" not in seen and p.is_alive()]
        if not alive or (deadline is not None and time.perf_counter() > deadline):
            break
        time.sleep(1.0)
    out = {}
    for variant, (proc, queue, seen) in runs.items():
        if proc.is_alive():
            proc.terminate()
            proc.join()
        start = seen.get("start")
        setup_s = f"{seen['setup'] - start:.0f} s" if "setup" in seen else "unfinished"
        if "done" in seen:
            out[variant] = f"finished in {seen['done'] - start:.0f} s (setup {setup_s})"
        else:
            out[variant] = f"not finished after {bound:.0f} s, stopped (setup {setup_s})"
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3, help="repetitions of the grid loop")
    ap.add_argument("--explicit-bound", type=float, metavar="SECONDS", default=None,
                    help="also try linearize(A_and_B=True), stopped after SECONDS")
    args = ap.parse_args()

    ref = benchmark_parameters()
    assert max(abs(trail_parameters(0.08)[k] - ref[k]) for k in ref) < 1e-12

    t_all = time.perf_counter()
    fM, fA, PT, idx, times, (mshape, ashape, state) = setup()
    t_setup = sum(times.values())
    print(f"implicit linearisation: M {mshape[0]}x{mshape[1]}, A {ashape[0]}x{ashape[1]}, "
          f"state (q_i, u_i) = ({', '.join(state)}); 4 x 4 block rows/cols {idx}")

    # The 4 lean/steer rows must not depend on the dropped states.
    others = [k for k in range(len(state)) if k not in idx]
    coupling = 0.0
    for c in (0.0, 0.08, 0.2):
        values = trail_parameters(c)
        p = [values[k] for k in PARAMETERS]
        for speed in (0.0, 5.0, 10.0):
            full = state_matrix(fM, fA, PT, speed, p)
            coupling = max(coupling, np.abs(full[np.ix_(idx, others)]).max())
    print(f"max |entry| coupling the 4 lean/steer rows to the 6 dropped states: {coupling:.1e}")

    n_points = len(V_GRID) * len(C_GRID)
    loop_times = []
    for _ in range(args.runs):
        ev, t = clock(lambda: sweep(fM, fA, PT, idx, V_GRID, C_GRID))
        loop_times.append(t)
    t_loop = statistics.median(loop_times)

    cc, vv = np.meshgrid(C_GRID, V_GRID, indexing="ij")
    closed = np.linalg.eigvals(benchmark_state_matrix(vv, dict(BENCHMARK, c=cc)))
    diff, where = max_difference(ev, closed)
    print("eigenvalues at v = 5, c = 0.08 (user's route): "
          + ", ".join(f"{z.real:.6f}{z.imag:+.6f}j" for z in np.sort_complex(ev[40, 100])))

    print()
    print("| step | time |")
    print("|---|---|")
    for label, t in times.items():
        print(f"| {label} | {t:.2f} s |")
    print(f"| **setup total** (model + linearisation + lambdify) | **{t_setup:.1f} s** |")
    print(f"| grid loop, {len(V_GRID)} v x {len(C_GRID)} c = {n_points} points "
          f"(median of {args.runs}) | {t_loop:.2f} s |")
    print(f"| per point (lambdified M, A; solve 16x16; eigvals 4x4) | "
          f"{1e6 * t_loop / n_points:.0f} us |")
    print(f"| points per second | {n_points / t_loop:.0f} |")
    print(f"| max abs eigenvalue difference vs closed form (all {n_points} points) | "
          f"{diff:.1e} (at v = {V_GRID[where[1]]:.2f}, c = {C_GRID[where[0]]:.3f}) |")
    print(f"| wall time of the above | {time.perf_counter() - t_all:.1f} s |")

    if args.explicit_bound is not None:
        print()
        print(f"linearize(op_point, A_and_B=True, linear_solver='CRAMER'), bound "
              f"{args.explicit_bound:.0f} s from to_linearizer(), both in parallel:")
        for variant, outcome in explicit_attempts(args.explicit_bound).items():
            label = ("all parameters symbolic" if variant == "symbolic" else
                     "all but v, forkoffset, framelength, forkcg3 numeric")
            print(f"  {label}: {outcome}")


if __name__ == "__main__":
    main()
