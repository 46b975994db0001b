"""Right-hand-side cost per state: nhham beside PyDy and LagrangesMethod + lambdify.

The N-link snake (nhham.models.snake: N links with a knife edge each, n = N + 2,
m = N) for N = 1, 2, 4, 8, 12, one state and batches of 10^4 states, all in
this process:

- nhham, compiled C backend: ``model.rhs(t, y)`` (the call an integrator makes),
  the bare ctypes call underneath it (the fused generated C plus the call),
  and a batch of 10^4 states (``model.rhs(t, Y)``, Y of shape (10^4, 2n));
- nhham, numpy backend: the same calls;
- nhham closed form P(xi_L) compiled to C (symbolic solve, fused), N <= 2 only:
  deriving it symbolically gets expensive quickly;
- PyDy: Kane's method + ``generate_ode_function(generator="cython")``;
- sympy ``LagrangesMethod`` + ``lambdify`` + ``numpy.linalg.solve``.

Run: ``python bench/rhs.py [--quick]`` (needs the ``bench`` extra: pydy, cython).
Prints medians in microseconds per state and the ratios; no assertions.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

import os

import numpy as np
import sympy as sp

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from nhham.codegen import numeric_model
from nhham.models import snake


def median_time(fn, number, repeat=5):
    """Median over ``repeat`` runs of the time per call of ``fn`` (seconds)."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - start) / number)
    return statistics.median(times)


def snake_states(model, k, seed=0):
    """k states of M_1: random q and v, velocities projected in the kinetic metric."""
    rng = np.random.default_rng(seed)
    n = model.n
    Y = np.empty((k, 2 * n))
    base = []
    for _ in range(min(k, 64)):
        y = np.concatenate([rng.uniform(-0.5, 0.5, n), rng.normal(size=n)])
        y[2:n] = 0.3 * np.cumsum(rng.uniform(-0.4, 0.4, n - 2))  # a gently bent snake
        base.append(model.project(y).y)
    for i in range(k):
        Y[i] = base[i % len(base)]
    return Y


# ------------------------------------------------------------- PyDy (Kane)
def pydy_snake(N, m=1.0, l=1.0):
    """The same snake with sympy.physics.mechanics.KanesMethod.

    Speeds u_i = q_i'; independent speeds (x', theta1'), dependent the rest
    (solved from the N knife-edge constraints). Returns (kane, q, u, constants,
    constant values).
    """
    from sympy.physics.mechanics import (KanesMethod, Point, ReferenceFrame, RigidBody,
                                         dynamicsymbols, inertia)

    q = dynamicsymbols(f"x y th1:{N + 1}")
    u = dynamicsymbols(f"u0:{N + 2}")
    mm, ll = sp.symbols("m l")
    frame = ReferenceFrame("N")
    origin = Point("O")
    origin.set_vel(frame, 0)
    links = [frame.orientnew(f"A{i}", "Axis", [q[2 + i], frame.z]) for i in range(N)]
    centres = [origin.locatenew("P0", q[0] * frame.x + q[1] * frame.y)]
    for i in range(1, N):
        centres.append(centres[-1].locatenew(f"P{i}", ll / 2 * links[i - 1].x + ll / 2 * links[i].x))
    kd = {sp.diff(qi, dynamicsymbols._t): ui for qi, ui in zip(q, u)}
    bodies, constraints = [], []
    for i, (A, P) in enumerate(zip(links, centres)):
        A.set_ang_vel(frame, u[2 + i] * frame.z)
        vel = P.pos_from(origin).dt(frame).subs(kd)
        P.set_vel(frame, vel)
        bodies.append(RigidBody(f"B{i}", P, A, mm, (inertia(A, 0, 0, mm * ll**2 / 12), P)))
        constraints.append(sp.expand(vel.dot(A.y)))
    kane = KanesMethod(frame, q_ind=list(q), u_ind=[u[0], u[2]],
                       u_dependent=[u[1]] + list(u[3:]),
                       kd_eqs=[sp.diff(qi, dynamicsymbols._t) - ui for qi, ui in zip(q, u)],
                       velocity_constraints=constraints)
    kane.kanes_equations(bodies, [])
    return kane, q, u, [mm, ll], np.array([m, l])


def pydy_rhs(N):
    from pydy.codegen.ode_function_generators import generate_ode_function

    kane, q, u, consts, values = pydy_snake(N)
    speeds = list(kane.u)  # PyDy orders speeds as independent, then dependent
    perm = np.array([list(u).index(s) for s in speeds])
    f = generate_ode_function(kane.forcing_full, q, speeds, consts,
                              mass_matrix=kane.mass_matrix_full, generator="cython")
    return f, values, perm


def lagranges_rhs(N):
    """LagrangesMethod on the same L and constraints, lambdified; per state solve."""
    from sympy.physics.mechanics import LagrangesMethod, dynamicsymbols

    system = snake(N)
    q = dynamicsymbols(" ".join(s.name for s in system.coordinates))
    q = list(q) if isinstance(q, (list, tuple)) else [q]
    t = dynamicsymbols._t
    sub = {s: qq for s, qq in zip(system.coordinates, q)}
    sub.update({v: sp.diff(qq, t) for v, qq in zip(system.velocities, q)})
    sub.update(system.parameter_values)
    L = system.lagrangian.xreplace(sub)
    cons = [c.xreplace(sub) for c in system.phi]
    lm = LagrangesMethod(L, q, nonhol_coneqs=cons)
    lm.form_lagranges_equations()
    qd = [sp.diff(qq, t) for qq in q]
    args = q + qd
    M = sp.lambdify(args, lm.mass_matrix_full, "numpy", cse=True)
    F = sp.lambdify(args, lm.forcing_full, "numpy", cse=True)
    n = len(q)

    def rhs(y):
        sol = np.linalg.solve(np.asarray(M(*y), dtype=float), np.asarray(F(*y), dtype=float)[:, 0])
        return sol[:2 * n]

    return rhs


# ------------------------------------------------------------------ main
def measure(N, batch_k=10_000, with_peers=True, number=2000):
    row = {"N": N}
    system = snake(N)
    t0 = time.perf_counter()
    model_c = numeric_model(system, backend="c")
    row["codegen_s"] = time.perf_counter() - t0
    model_np = numeric_model(system, backend="numpy")
    Y = snake_states(model_c, batch_k)
    y = Y[0].copy()
    row["nhham_c_single"] = median_time(lambda: model_c.rhs(0.0, y), number)
    pext = model_c._pext0
    row["nhham_c_ctypes"] = median_time(lambda: model_c.compiled.one(y, pext), number)
    row["nhham_c_batch"] = median_time(lambda: model_c.rhs(0.0, Y), 3, repeat=3) / batch_k
    row["nhham_np_single"] = median_time(lambda: model_np.rhs(0.0, y), max(50, number // 20))
    row["nhham_np_batch"] = median_time(lambda: model_np.rhs(0.0, Y), 1, repeat=3) / batch_k
    ref = model_c.rhs(0.0, y)
    if N <= 2:
        t0 = time.perf_counter()
        closed = numeric_model(system, backend="c", path="closed_form")
        row["closed_codegen_s"] = time.perf_counter() - t0
        assert np.allclose(closed.rhs(0.0, y), ref, rtol=1e-10, atol=1e-10)
        row["closed_c_single"] = median_time(lambda: closed.rhs(0.0, y), number)
        row["closed_c_batch"] = median_time(lambda: closed.rhs(0.0, Y), 3, repeat=3) / batch_k
    if with_peers:
        try:
            t0 = time.perf_counter()
            f, values, perm = pydy_rhs(N)
            row["pydy_codegen_s"] = time.perf_counter() - t0
            n = model_c.n
            # PyDy's state is (q, u), u = q' with the independent speeds first.
            order = np.concatenate([np.arange(n), n + perm])
            yp, Yp = y[order], np.ascontiguousarray(Y[:, order])
            out = f(yp, 0.0, values)
            assert np.allclose(out, ref[order], rtol=1e-8, atol=1e-8), (out, ref[order])
            row["pydy_single"] = median_time(lambda: f(yp, 0.0, values), number)
            try:
                row["pydy_batch"] = median_time(lambda: f(Yp, 0.0, values), 1, repeat=3) / batch_k
            except Exception:  # older PyDy: no 2-D states
                row["pydy_batch"] = float("nan")
        except ImportError as exc:
            print(f"PyDy unavailable ({exc}); pip install pydy cython", file=sys.stderr)
        t0 = time.perf_counter()
        lag = lagranges_rhs(N)
        row["lagranges_codegen_s"] = time.perf_counter() - t0
        assert np.allclose(lag(y), ref, rtol=1e-8, atol=1e-8)
        row["lagranges_single"] = median_time(lambda: lag(y), max(50, number // 20))
    return row


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="N = 1, 2, 4 and fewer repeats")
    parser.add_argument("--no-peers", action="store_true", help="skip PyDy and LagrangesMethod")
    args = parser.parse_args(argv)
    Ns = (1, 2, 4) if args.quick else (1, 2, 4, 8, 12)
    rows = [measure(N, with_peers=not args.no_peers, number=500 if args.quick else 2000)
            for N in Ns]
    us = lambda v: "-" if v is None or v != v else f"{1e6 * v:.2f}"  # noqa: E731
    print("right-hand side, microseconds per state (median); snake with N links")
    head = ["N", "nhham C rhs()", "bare C call", "nhham C batch", "nhham numpy rhs()",
            "numpy batch", "closed-form C rhs()", "PyDy Cython", "PyDy batch",
            "Lagranges+lambdify"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in rows:
        vals = [str(r["N"]), us(r["nhham_c_single"]), us(r["nhham_c_ctypes"]),
                us(r["nhham_c_batch"]), us(r["nhham_np_single"]), us(r["nhham_np_batch"]),
                us(r.get("closed_c_single")), us(r.get("pydy_single")), us(r.get("pydy_batch")),
                us(r.get("lagranges_single"))]
        print("| " + " | ".join(vals) + " |")
    print()
    for r in rows:
        ratios = []
        if "pydy_single" in r:
            ratios.append(f"PyDy/nhham-C {r['pydy_single'] / r['nhham_c_single']:.1f}x")
        if "lagranges_single" in r:
            ratios.append(f"Lagranges/nhham-C {r['lagranges_single'] / r['nhham_c_single']:.0f}x")
        ratios.append(f"rhs()/bare-C {r['nhham_c_single'] / r['nhham_c_ctypes']:.2f}x")
        if "closed_c_single" in r:
            ratios.append(f"rhs()/closed-form-C {r['nhham_c_single'] / r['closed_c_single']:.2f}x")
        ratios.append(f"codegen {r['codegen_s']:.1f} s")
        print(f"N = {r['N']}: " + ", ".join(ratios))
    return rows


if __name__ == "__main__":
    main()
