"""Right-hand-side cost per state: nhham beside a hand-written C rhs, PyDy and Lagranges.

The N-link snake (nhham.models.snake: N links with a knife edge each, n = N + 2,
m = N) for N = 1, 2, 4, 8, 12, one state and batches of 10^4 states, all in
this process:

- nhham, compiled C backend: ``model.rhs(t, y)`` (the call an integrator makes),
  the layers under it -- the CPython entry point alone (``compiled.ext.rhs``:
  one C call that returns a new array) and the ctypes route
  (``compiled.one``: copy into a scratch buffer + ctypes call) -- and a batch
  of 10^4 states (``model.rhs(t, Y)``: one C call looping over the states, so
  the per-state figure is the fused generated C itself);
- a hand-fused C rhs of the same snake (bench/snake_hand.c: derived by hand
  from the link Jacobians, one sincos per angle, O(N) recursions, the same
  Cholesky/Schur solve), per state in a C loop over 10^4 states ("hand C",
  the compute floor) and one state through a bare ctypes call with
  preallocated buffers;
- nhham, numpy backend: the same calls;
- nhham closed form P(xi_L) compiled to C (symbolic solve, fused), N <= 2 only:
  deriving it symbolically gets expensive quickly;
- PyDy: Kane's method + ``generate_ode_function(generator="cython")``;
- sympy ``LagrangesMethod`` + ``lambdify`` + ``numpy.linalg.solve``;
- with ``--baseline REV``: nhham's codegen.py and numeric.py of the git
  revision REV (e.g. the last commit) loaded beside the current ones, the same
  calls: before/after in one process.

Run: ``python bench/rhs.py [--quick] [--baseline REV]`` (needs the ``bench``
extra: pydy, cython). Prints medians in microseconds per state and the
ratios; no assertions (but every variant is checked against nhham's values).
``python bench/rhs.py --links 8 12 --flags=-O3 '--flags=-O3 -march=native'``
compares compiler flags on the batched rhs instead.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import statistics
import subprocess
import sys
import time
import types

import numpy as np
import sympy as sp

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from nhham.numerics.codegen import compile_c, numeric_model
from nhham.system.models import snake

HERE = os.path.dirname(os.path.abspath(__file__))


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


# ------------------------------------------------------------- hand-fused C
def hand_rhs(N):
    """bench/snake_hand.c compiled for N links (same flags as nhham's code):
    (single(y) -> out, batch(Y) -> OUT, the bare ctypes call for one state)."""
    with open(os.path.join(HERE, "snake_hand.c")) as fh:
        source = f"#define NL {N}\n" + fh.read()
    lib = ctypes.CDLL(compile_c(source))
    p = np.array([1.0, 1.0])  # m, l as in nhham.models.snake's defaults
    pp = ctypes.c_void_p(p.ctypes.data)
    n2 = 2 * (N + 2)
    ybuf, obuf = np.zeros(n2), np.zeros(n2)
    yp, op = ctypes.c_void_p(ybuf.ctypes.data), ctypes.c_void_p(obuf.ctypes.data)
    f1, fk = lib.hand_rhs, lib.hand_rhs_batch

    def single(y):
        ybuf[:] = y
        f1(yp, op, pp)
        return obuf.copy()

    def batch(Y):
        OUT = np.empty_like(Y)
        fk(ctypes.c_int(Y.shape[0]), ctypes.c_void_p(Y.ctypes.data),
           ctypes.c_void_p(OUT.ctypes.data), pp)
        return OUT

    return single, batch, lambda: f1(yp, op, pp), (ybuf, obuf, p)


# ------------------------------------------------------------------ baseline
def load_baseline(rev):
    """numeric_model of git revision ``rev``: its codegen.py and numeric.py
    executed as nhham._baseline_codegen / nhham._baseline_numeric (the rest of
    the package is the current one). Read-only git (``git show``)."""
    root = os.path.dirname(HERE)

    def show(path):
        return subprocess.run(["git", "-C", root, "show", f"{rev}:{path}"], check=True,
                              capture_output=True, text=True).stdout

    sources = {"nhham._baseline_numeric": show("nhham/numeric.py"),
               "nhham._baseline_codegen": show("nhham/codegen.py").replace(
                   "from .numeric import", "from ._baseline_numeric import")}
    for name, text in sources.items():
        module = types.ModuleType(name)
        module.__package__ = "nhham"
        module.__file__ = f"<{rev}:{name}>"
        sys.modules[name] = module
        exec(compile(text, module.__file__, "exec"), module.__dict__)
    return sys.modules["nhham._baseline_codegen"].numeric_model


# ------------------------------------------------------------ compiler flags
def compare_flags(N, variants, batch_k=10_000, rounds=15):
    """The generated C of the N-link snake compiled with the default flags plus
    each variant, batched rhs per state timed in interleaved rounds (so that
    the machine's noise hits every variant alike); medians over the rounds."""
    model = numeric_model(snake(N), backend="c")
    Y = snake_states(model, batch_k)
    pext = model.parameter_block().pointer
    libs = {}
    for flags in variants:
        path = compile_c(model.c_source, flags=flags.split())
        from nhham.numerics.kernels import CompiledRHS

        libs[flags or "-O2 (default)"] = CompiledRHS.load(path, model.layout)
    ref = model.rhs(0.0, Y)
    times = {name: [] for name in libs}
    for _ in range(rounds):
        for name, lib in libs.items():
            start = time.perf_counter()
            OUT, bad = lib.batch(Y, pext)
            times[name].append((time.perf_counter() - start) / batch_k)
            assert not bad and np.allclose(OUT[:, :2 * model.n], ref, rtol=1e-10, atol=1e-10)
    return {name: statistics.median(t) for name, t in times.items()}


# ------------------------------------------------------------------ main
def measure(N, batch_k=10_000, with_peers=True, number=2000, baseline=None):
    row = {"N": N}
    system = snake(N)
    t0 = time.perf_counter()
    model_c = numeric_model(system, backend="c")
    row["codegen_s"] = time.perf_counter() - t0
    model_np = numeric_model(system, backend="numpy")
    Y = snake_states(model_c, batch_k)
    y = Y[0].copy()
    ref = model_np.rhs(0.0, y)
    assert np.allclose(model_c.rhs(0.0, y), ref, rtol=1e-11, atol=1e-11)
    assert np.allclose(model_c.rhs(0.0, Y), model_np.rhs(0.0, Y), rtol=1e-10, atol=1e-10)
    single, batch, bare, keep = hand_rhs(N)
    assert np.allclose(single(y), ref, rtol=1e-11, atol=1e-11)
    assert np.allclose(batch(Y), model_np.rhs(0.0, Y), rtol=1e-10, atol=1e-10)
    block = model_c.parameter_block()
    pext, addr = block.pointer, block.address
    ext = model_c.compiled.ext
    # The C-level figures first and last (the VM is noisy): medians of both passes.
    c_batch = [median_time(lambda: model_c.rhs(0.0, Y), 3, repeat=5) / batch_k]
    h_batch = [median_time(lambda: batch(Y), 3, repeat=5) / batch_k]
    row["nhham_c_single"] = median_time(lambda: model_c.rhs(0.0, y), number, repeat=7)
    if ext is not None:
        row["nhham_c_ext"] = median_time(lambda: ext.rhs(y, addr), number, repeat=7)
    row["nhham_c_ctypes"] = median_time(lambda: model_c.compiled.one(y, pext), number, repeat=7)
    row["hand_single"] = median_time(bare, number, repeat=7)
    c_batch.append(median_time(lambda: model_c.rhs(0.0, Y), 3, repeat=5) / batch_k)
    h_batch.append(median_time(lambda: batch(Y), 3, repeat=5) / batch_k)
    row["nhham_c_batch"], row["hand_batch"] = min(c_batch), min(h_batch)
    row["nhham_np_single"] = median_time(lambda: model_np.rhs(0.0, y), max(50, number // 20))
    row["nhham_np_batch"] = median_time(lambda: model_np.rhs(0.0, Y), 1, repeat=3) / batch_k
    if baseline is not None:
        old = baseline(system, backend="c")
        assert np.allclose(old.rhs(0.0, y), ref, rtol=1e-10, atol=1e-10)
        row["base_single"] = median_time(lambda: old.rhs(0.0, y), number, repeat=7)
        row["base_batch"] = median_time(lambda: old.rhs(0.0, Y), 3, repeat=5) / batch_k
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
    parser.add_argument("--baseline", metavar="REV",
                        help="also time codegen.py/numeric.py of this git revision")
    parser.add_argument("--links", type=int, nargs="*", help="snake sizes (default 1 2 4 8 12)")
    parser.add_argument("--flags", action="append", metavar="FLAGS",
                        help="only compare extra compiler flags against the default on the "
                             "batched rhs; repeat it: --flags=-O3 '--flags=-O3 -march=native'")
    args = parser.parse_args(argv)
    if args.flags is not None:
        variants = [""] + list(args.flags)
        print("batched rhs, microseconds per state (median of 15 interleaved rounds of 10^4)")
        print("| N | " + " | ".join(v or "-O2 (default)" for v in variants) + " |")
        print("|---|" + "---|" * len(variants))
        for N in args.links or (8, 12):
            res = compare_flags(N, variants)
            print(f"| {N} | " + " | ".join(f"{1e6 * v:.2f}" for v in res.values()) + " |")
        return None
    Ns = args.links or ((1, 2, 4) if args.quick else (1, 2, 4, 8, 12))
    baseline = load_baseline(args.baseline) if args.baseline else None
    rows = [measure(N, with_peers=not args.no_peers, number=500 if args.quick else 2000,
                    baseline=baseline) for N in Ns]
    us = lambda v: "-" if v is None or v != v else f"{1e6 * v:.2f}"  # noqa: E731
    print("right-hand side, microseconds per state (median); snake with N links")
    cols = [("N", None), ("nhham C rhs()", "nhham_c_single"),
            ("CPython entry", "nhham_c_ext"), ("ctypes call", "nhham_c_ctypes"),
            ("nhham C batch", "nhham_c_batch"), ("hand C (batch)", "hand_batch"),
            ("hand C ctypes", "hand_single"), ("numpy rhs()", "nhham_np_single"),
            ("numpy batch", "nhham_np_batch"), ("closed-form C rhs()", "closed_c_single"),
            ("closed-form C batch", "closed_c_batch"),
            ("PyDy Cython", "pydy_single"), ("PyDy batch", "pydy_batch"),
            ("Lagranges+lambdify", "lagranges_single")]
    if baseline is not None:
        cols[1:1] = [(f"{args.baseline} rhs()", "base_single"),
                     (f"{args.baseline} batch", "base_batch")]
    print("| " + " | ".join(c for c, _ in cols) + " |")
    print("|" + "---|" * len(cols))
    for r in rows:
        print("| " + " | ".join([str(r["N"])] + [us(r.get(k)) for _, k in cols[1:]]) + " |")
    print()
    for r in rows:
        ratios = [f"rhs()/hand-C {r['nhham_c_single'] / r['hand_batch']:.2f}x",
                  f"batch/hand-C {r['nhham_c_batch'] / r['hand_batch']:.2f}x",
                  f"rhs()/batch {r['nhham_c_single'] / r['nhham_c_batch']:.2f}x"]
        if "base_single" in r:
            ratios.append(f"{args.baseline}/now rhs() {r['base_single'] / r['nhham_c_single']:.1f}x"
                          f", batch {r['base_batch'] / r['nhham_c_batch']:.1f}x")
        if "pydy_single" in r:
            ratios.append(f"PyDy/nhham-C {r['pydy_single'] / r['nhham_c_single']:.1f}x")
        if "lagranges_single" in r:
            ratios.append(f"Lagranges/nhham-C {r['lagranges_single'] / r['nhham_c_single']:.0f}x")
        if "closed_c_single" in r:
            ratios.append(f"rhs()/closed-form-C {r['nhham_c_single'] / r['closed_c_single']:.2f}x")
        ratios.append(f"codegen {r['codegen_s']:.1f} s")
        print(f"N = {r['N']}: " + ", ".join(ratios))
    return rows


if __name__ == "__main__":
    main()
