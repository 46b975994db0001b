"""Work-precision of every nhham method, beside PyDy's own pipeline.

Problems: the Chaplygin sleigh, the rolling disk and the 8-link snake
(``nhham.models``). For each: the full work-precision table of
:func:`nhham.workprecision.work_precision` (every scipy method with and without
projection, RATTLE, RATTLE4, RK4; error at t_end against a 30-digit mpmath
reference), then PyDy's pipeline on the same system -- Kane's method,
``generate_ode_function(generator="cython")`` and its default integrator
(``scipy.integrate.odeint``, i.e. LSODA, as ``pydy.system.System.integrate``
uses) -- at rtol = atol = 1e-3 .. 1e-13, with its error against the same
reference and the constraint residual along its trajectory. Finally the time
to reach relative error 1e-6 and 1e-10 for both, and the ratio.

RK23, RK45 and DOP853 run as one compiled loop when the model is compiled
(``simulate(loop="auto")``); as the in-process baseline for that, DOP853 (with
and without projection) is also run through scipy's Python loop
(``loop="scipy"``, the previous path) on the same model. A summary table of
all problems closes the output.

Run: ``python bench/work_precision.py [--quick] [--plot DIR] [--repeats K]``
(``bench`` extra).
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import sympy as sp  # noqa: E402

from nhham import models  # noqa: E402
from nhham.numerics.codegen import numeric_model  # noqa: E402
from nhham.numerics.reference import reference_solution  # noqa: E402
from nhham.numerics.workprecision import work_precision  # noqa: E402


# ------------------------------------------------------------ PyDy models
def _kane(frame, q, u, u_ind, u_dep, bodies, constraints):
    from sympy.physics.mechanics import KanesMethod, dynamicsymbols

    t = dynamicsymbols._t
    kane = KanesMethod(frame, q_ind=list(q), u_ind=u_ind, u_dependent=u_dep,
                       kd_eqs=[sp.diff(qi, t) - ui for qi, ui in zip(q, u)],
                       velocity_constraints=constraints)
    kane.kanes_equations(bodies, [])
    return kane


def pydy_sleigh(m=1.0, I=0.25, a=0.5):
    """Sleigh as in nhham.models.chaplygin_sleigh: (x, y) centre of mass, blade
    at distance a behind it; dependent speed y' (needs cos(theta) != 0)."""
    from sympy.physics.mechanics import (Point, ReferenceFrame, RigidBody, dynamicsymbols,
                                         inertia)

    q = dynamicsymbols("x y theta")
    u = dynamicsymbols("u0:3")
    mm, ii, aa = sp.symbols("m I a")
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q[2], N.z])
    A.set_ang_vel(N, u[2] * N.z)
    O = Point("O")
    O.set_vel(N, 0)
    G = O.locatenew("G", q[0] * N.x + q[1] * N.y)
    G.set_vel(N, u[0] * N.x + u[1] * N.y)
    blade = G.locatenew("P", -aa * A.x)
    blade.v2pt_theory(G, N, A)
    body = RigidBody("B", G, A, mm, (inertia(A, 0, 0, ii), G))
    cons = [blade.vel(N).dot(A.y)]
    kane = _kane(N, q, u, [u[0], u[2]], [u[1]], [body], cons)
    return kane, q, u, [mm, ii, aa], np.array([m, I, a])


def pydy_disk(m=1.0, I1=0.25, I2=0.5, R=1.0):
    """Vertical rolling disk as in nhham.models.rolling_disk; dependent x', y'."""
    from sympy.physics.mechanics import (Point, ReferenceFrame, RigidBody, dynamicsymbols,
                                         inertia)

    q = dynamicsymbols("x y theta phi")
    u = dynamicsymbols("u0:4")
    mm, i1, i2, rr = sp.symbols("m I1 I2 R")
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q[2], N.z])
    B = A.orientnew("B", "Axis", [q[3], A.y])
    A.set_ang_vel(N, u[2] * N.z)
    B.set_ang_vel(A, u[3] * A.y)
    O = Point("O")
    O.set_vel(N, 0)
    G = O.locatenew("G", q[0] * N.x + q[1] * N.y)
    G.set_vel(N, u[0] * N.x + u[1] * N.y)
    body = RigidBody("D", G, B, mm, (inertia(B, i1, i2, i1), G))
    th = q[2]
    cons = [u[0] - rr * sp.cos(th) * u[3], u[1] - rr * sp.sin(th) * u[3]]
    kane = _kane(N, q, u, [u[2], u[3]], [u[0], u[1]], [body], cons)
    return kane, q, u, [mm, i1, i2, rr], np.array([m, I1, I2, R])


def pydy_pipeline(kane_tuple):
    """Cython right-hand side and the permutation of its speeds to ours."""
    from pydy.codegen.ode_function_generators import generate_ode_function

    kane, q, u, consts, values = kane_tuple
    speeds = list(kane.u)
    perm = np.array([list(u).index(s) for s in speeds])
    f = generate_ode_function(kane.forcing_full, q, speeds, consts,
                              mass_matrix=kane.mass_matrix_full, generator="cython")
    return f, values, perm


def pydy_runs(f, values, perm, model, y0, t_end, y_ref, tolerances, repeats):
    """odeint (PyDy's default integrator) at each tolerance: rows of numbers."""
    from scipy.integrate import odeint

    n = model.n
    order = np.concatenate([np.arange(n), n + perm])
    inverse = np.argsort(order)
    x0 = y0[order]
    t = np.linspace(0.0, t_end, 201)
    rows = []
    for tol in tolerances:
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            sol, info = odeint(f, x0, t, args=(values,), rtol=tol, atol=tol, full_output=True,
                               mxstep=10**7)
            times.append(time.perf_counter() - start)
        ours = sol[:, inverse]
        err = float(np.linalg.norm(ours[-1] - y_ref) / np.linalg.norm(y_ref))
        res = float(np.max(np.abs(model.residuals(ours))))
        rows.append({"tol": tol, "error": err, "wall_time_s": statistics.median(times),
                     "nfev": int(info["nfe"][-1]), "constraint_residual": res})
    return rows


# --------------------------------------------------------------- problems
def problems(quick):
    sleigh = models.chaplygin_sleigh()
    th0, u0, w0, a = -1.1, 0.3, 1.2, 0.5
    e1, e2 = np.array([math.cos(th0), math.sin(th0)]), np.array([-math.sin(th0), math.cos(th0)])
    v = u0 * e1 + a * w0 * e2
    out = [("Chaplygin sleigh", sleigh, np.array([0, 0, th0, v[0], v[1], w0]), 10.0,
            pydy_sleigh, {})]
    disk = models.rolling_disk()
    th, s, w, R = 0.3, 2.0, 1.1, 1.0
    out.append(("rolling disk", disk, np.array([0.2, -0.1, th, 0.0, R * s * math.cos(th),
                                                 R * s * math.sin(th), w, s]), 10.0,
                pydy_disk, {}))
    if not quick:
        from rhs import pydy_snake, snake_states

        snake = models.snake(8)
        y0 = snake_states(numeric_model(snake), 1, seed=3)[0]
        out.append(("8-link snake", snake, y0, 5.0, lambda: pydy_snake(8),
                    {"steps": [5.0 / N for N in (50, 100, 200, 400)],
                     "reference_digits": 25}))
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="sleigh and disk, quick ladder")
    parser.add_argument("--plot", help="directory for work-precision diagrams (matplotlib)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    peer_tols = [10.0 ** -k for k in range(3, 14)]
    summary = []
    for name, system, y0, t_end, peer, extra in problems(args.quick):
        print(f"\n## {name}, t in [0, {t_end}]\n", flush=True)
        model = numeric_model(system)
        start = time.perf_counter()
        wp = work_precision(model, y0, (0.0, t_end), quick=args.quick, repeats=args.repeats,
                            **extra)
        print(wp.describe())
        print(f"(study took {time.perf_counter() - start:.0f} s)")
        if args.plot:
            from nhham.render.plotting import plot_work_precision, save_figure

            os.makedirs(args.plot, exist_ok=True)
            path = os.path.join(args.plot, name.replace(" ", "_") + ".png")
            print("diagram:", save_figure(plot_work_precision(wp), path))
        base = None
        if model.backend == "c":
            base = work_precision(model, y0, (0.0, t_end), methods=["DOP853"], loop="scipy",
                                  repeats=args.repeats, reference_digits=wp.reference_digits,
                                  tolerances=(1e-5, 1e-8, 1e-11) if args.quick else
                                  (1e-4, 1e-6, 1e-8, 1e-10, 1e-12))
            print("\nDOP853 through scipy's Python loop (loop='scipy', the previous path; same "
                  "model, same process):\n")
            print(base.table())
        ref = reference_solution(model, y0, (0.0, t_end), digits=wp.reference_digits,
                                 t_eval=[t_end])
        try:
            f, values, perm = pydy_pipeline(peer())
        except ImportError as exc:
            print(f"PyDy unavailable ({exc}); pip install pydy cython")
            continue
        rows = pydy_runs(f, values, perm, model, y0, t_end, ref.y[:, -1], peer_tols, args.repeats)
        print("\nPyDy (Kane + Cython + odeint/LSODA):\n")
        print("| rtol=atol | error at t_end | wall time [ms] | evaluations | constraint residual |")
        print("|---|---|---|---|---|")
        for r in rows:
            print(f"| {r['tol']:.0e} | {r['error']:.2e} | {1e3 * r['wall_time_s']:.2f} | "
                  f"{r['nfev']} | {r['constraint_residual']:.1e} |")
        print()
        for target in (1e-6, 1e-10):
            ours = {k: v for k, v in wp.time_to_solution(target).items() if v is not None}
            exact = {k: v for k, v in ours.items()
                     if all(r.constraint_residual <= 1e-12 for r in wp.rows
                            if r.method == k and r.status == 0 and r.error <= target)}
            peer_ok = [r["wall_time_s"] for r in rows if r["error"] <= target]
            peer_t = min(peer_ok) if peer_ok else None
            best = min(ours.items(), key=lambda kv: kv[1]) if ours else None
            best_exact = min(exact.items(), key=lambda kv: kv[1]) if exact else None
            line = f"relative error {target:.0e}: "
            line += (f"nhham best {best[0]} {1e3 * best[1]:.2f} ms" if best else "nhham: none")
            if best_exact:
                line += f"; best with residual <= 1e-12: {best_exact[0]} {1e3 * best_exact[1]:.2f} ms"
            slow = None
            if base is not None:
                slow_ok = [v for v in base.time_to_solution(target).values() if v is not None]
                slow = min(slow_ok) if slow_ok else None
                line += (f"; DOP853 with scipy's loop {1e3 * slow:.2f} ms" if slow
                         else "; scipy loop: not reached")
            line += f"; PyDy {1e3 * peer_t:.2f} ms" if peer_t else "; PyDy: not reached"
            if best and peer_t:
                line += f"; ratio PyDy/nhham = {peer_t / best[1]:.1f}x"
            print(line, flush=True)
            summary.append((name, target, best, best_exact, slow, peer_t))
    print("\nSummary: time to solution (medians of the repeats; ratio = PyDy / nhham best)\n")
    print("| problem | rel. error | nhham best | best with residual <= 1e-12 | "
          "DOP853, scipy's loop | PyDy | PyDy / nhham | scipy loop / nhham |")
    print("|---|---|---|---|---|---|---|---|")
    ms = lambda kv: f"{kv[0]} {1e3 * kv[1]:.2f} ms" if kv else "-"  # noqa: E731
    for name, target, best, best_exact, slow, peer_t in summary:
        ratio = f"{peer_t / best[1]:.1f}x" if best and peer_t else "-"
        speed = f"{slow / best[1]:.1f}x" if best and slow else "-"
        print(f"| {name} | {target:.0e} | {ms(best)} | {ms(best_exact)} | "
              f"{'-' if slow is None else f'{1e3 * slow:.2f} ms'} | "
              f"{'-' if peer_t is None else f'{1e3 * peer_t:.2f} ms'} | {ratio} | {speed} |")


if __name__ == "__main__":
    main()
