"""Derivation cost: nhham's dynamics ingredients vs sympy's LagrangesMethod.

For the N-link nonholonomic snake (:func:`nhham.models.snake`) this times, in
the same process and on the same system:

* ``system``: building and validating a fresh ``System`` from the snake's
  expressions (validation computes the Hessian W and the one-forms mu);
* ``ingredients``: ``lagrangian_geometry(system).ingredients`` -- W, the
  forcing F = dL/dq - (d2L/dq dv) v (so xi_L), mu and the drift (so P(xi_L)),
  every entry touched;
* ``LagrangesMethod``: ``LagrangesMethod(L, q, nonhol_coneqs=...)`` followed by
  ``form_lagranges_equations()`` (the comparable sympy step; converting the
  expressions to dynamicsymbols happens outside the timing).

L is written two ways (``--form``): ``compact`` (as nhham.models.snake
writes it) and ``chain`` (the sum of the links' kinetic energies as a user
would write it, unexpanded). sympy's global cache is cleared before every
timed run, so no run profits from derivatives an earlier one computed.
Every phase is timed both in CPU seconds of this process
(``time.process_time``; both sides are single-threaded sympy, and CPU time
stays meaningful on a shared, loaded machine) and in wall-clock seconds
(``time.perf_counter``). Each figure is the median of the runs. What counts
for nhham is System construction (validation included: a user cannot skip
it) plus the ingredients; the headline ratio is LagrangesMethod / that sum.
The size of L is reported as ``sympy.count_ops`` and ``len(str(L))``, and a
growth exponent k (time ~ size^k) is fitted by least squares on log-log data
for N >= 2.

Usage::

    python bench/derive.py                # N = 1 2 4 8 12, 3 runs, both forms
    python bench/derive.py --quick        # N <= 4, 1 run
    python bench/derive.py --N 2 4 --runs 5
    python bench/derive.py --profile 8 --form compact   # cProfile of system + ingredients
"""

from __future__ import annotations

import argparse
import cProfile
import os
import platform
import pstats
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import sympy as sp
from sympy.core.cache import clear_cache
from sympy.physics import mechanics as me

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from nhham import System  # noqa: E402
from nhham.lagrangian.geometry import lagrangian_geometry  # noqa: E402
from nhham.system.mechanics import to_lagranges_method  # noqa: E402
from nhham.system.models import snake, snake_chain_lagrangian  # noqa: E402

DEFAULT_N = (1, 2, 4, 8, 12)
QUICK_MAX_N = 4


# ------------------------------------------------------------------ systems
def snake_expressions(N, form):
    """Coordinates, L, constraints and parameter values of the N-link snake.

    ``compact``: L as nhham.models.snake writes it, v^T W v/2 expanded with
    the closed-form W (cos(theta_j - theta_k) entries). ``chain``: L as a
    user might write it, sum_i m |d/dt c_i|^2/2 + m l^2 theta_i'^2/24 with the
    centres c_i of :func:`nhham.models.snake_chain_lagrangian`, not expanded. Same
    physics (tests/test_models.py checks the identity), different sizes.
    """
    base = snake(N)
    q = base.coordinates
    if form == "compact":
        L = base.lagrangian
    elif form == "chain":
        L = snake_chain_lagrangian(N)
    else:
        raise ValueError(f"unknown form {form!r}")
    params = {p.name: value for p, value in base.parameter_values.items()}
    return q, L, base.constraints, params


# ------------------------------------------------------------------ timings
def _touch(ingredients):
    """Visit every entry so that nothing lazy escapes the timing."""
    count = 0
    for matrix in (ingredients.W, ingredients.forcing, ingredients.mu, ingredients.drift):
        for entry in matrix:
            count += entry is not None
    return count


def _clocks():
    return time.process_time(), time.perf_counter()


def time_nhham(exprs):
    """CPU and wall seconds: {'system', 'ingredients', 'total', + '_wall' variants}.

    One cold start (sympy cache cleared) per run; the two phases run in
    sequence as they would in use.
    """
    q, L, cons, params = exprs
    clear_cache()
    c0, w0 = _clocks()
    system = System(q, L, cons, parameters=params)
    c1, w1 = _clocks()
    _touch(lagrangian_geometry(system).ingredients)
    c2, w2 = _clocks()
    return dict(system=c1 - c0, ingredients=c2 - c1, total=c2 - c0,
                system_wall=w1 - w0, ingredients_wall=w2 - w1, total_wall=w2 - w0)


def time_lagranges_method(exprs):
    """(CPU s, wall s) for LagrangesMethod + form_lagranges_equations, cold cache."""
    q, L, cons, params = exprs
    lm, qs, _ = to_lagranges_method(System(q, L, cons, parameters=params))
    L_dyn, cons_dyn = lm._L[0], list(lm.coneqs)
    clear_cache()
    c0, w0 = _clocks()
    me.LagrangesMethod(L_dyn, list(qs), nonhol_coneqs=cons_dyn).form_lagranges_equations()
    c1, w1 = _clocks()
    return c1 - c0, w1 - w0


def measure(Ns, runs, form, with_lm=True):
    rows = []
    nan = float("nan")
    for N in Ns:
        exprs = snake_expressions(N, form)
        L = exprs[1]
        nh = [time_nhham(exprs) for _ in range(runs)]
        row = dict(N=N, n=N + 2, m=N, ops=sp.count_ops(L), chars=len(str(L)))
        for key in nh[0]:
            row[key] = statistics.median(t[key] for t in nh)
        lm = [time_lagranges_method(exprs) for _ in range(runs)] if with_lm else [(nan, nan)]
        row["lm"] = statistics.median(c for c, _ in lm)
        row["lm_wall"] = statistics.median(w for _, w in lm)
        rows.append(row)
        print(f"  [{form}] N={N:3d}: system {row['system']:.3f}s ingredients "
              f"{row['ingredients']:.3f}s LagrangesMethod {row['lm']:.3f}s (CPU); "
              f"nhham {row['total_wall']:.3f}s LagrangesMethod {row['lm_wall']:.3f}s (wall)",
              file=sys.stderr, flush=True)
    return rows


# ------------------------------------------------------------------ report
def growth_exponent(rows, key):
    """Least-squares slope of log(time) against log(count_ops(L)), N >= 2."""
    pts = [(r["ops"], r[key]) for r in rows if r["N"] >= 2 and r[key] == r[key] and r[key] > 0]
    if len(pts) < 2:
        return float("nan")
    x = np.log([p[0] for p in pts])
    y = np.log([p[1] for p in pts])
    return float(np.polyfit(x, y, 1)[0])


def table(rows):
    lines = [
        "| N | n | m | ops(L) | len(str(L)) | nhham system CPU (s) | nhham ingredients CPU (s) "
        "| nhham total CPU (s) | LagrangesMethod CPU (s) | **LM / nhham total, CPU** "
        "| nhham total wall (s) | LagrangesMethod wall (s) | LM / nhham total, wall |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['N']} | {r['n']} | {r['m']} | {r['ops']} | {r['chars']} "
            f"| {r['system']:.3f} | {r['ingredients']:.3f} | {r['total']:.3f} "
            f"| {r['lm']:.3f} | **{r['lm'] / r['total']:.1f}x** "
            f"| {r['total_wall']:.3f} | {r['lm_wall']:.3f} | {r['lm_wall'] / r['total_wall']:.1f}x |")
    lines.append("")
    lines.append("Fitted growth exponent k, time ~ count_ops(L)^k (N >= 2, CPU): "
                 f"nhham ingredients {growth_exponent(rows, 'ingredients'):.2f}, "
                 f"nhham system {growth_exponent(rows, 'system'):.2f}, "
                 f"nhham system + ingredients {growth_exponent(rows, 'total'):.2f}, "
                 f"LagrangesMethod {growth_exponent(rows, 'lm'):.2f}.")
    return "\n".join(lines)


def environment():
    return (f"Python {platform.python_version()}, sympy {sp.__version__}, "
            f"{platform.machine()} with {os.cpu_count()} CPU(s), {platform.system()}")


def profile(N, form, limit=25):
    """cProfile of System construction + ingredients from a cold cache."""
    q, L, cons, params = snake_expressions(N, form)
    clear_cache()
    prof = cProfile.Profile()
    prof.enable()
    system = System(q, L, cons, parameters=params)
    _touch(lagrangian_geometry(system).ingredients)
    prof.disable()
    pstats.Stats(prof).sort_stats("cumulative").print_stats(limit)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--N", type=int, nargs="+", default=list(DEFAULT_N),
                        help="numbers of links (default 1 2 4 8 12)")
    parser.add_argument("--runs", type=int, default=3, help="runs per N (median; default 3)")
    parser.add_argument("--quick", action="store_true",
                        help=f"cap N at {QUICK_MAX_N} and use one run")
    parser.add_argument("--no-lm", action="store_true", help="skip LagrangesMethod")
    parser.add_argument("--form", choices=("compact", "chain", "both"), default="both",
                        help="how L is written (default both; see snake_expressions)")
    parser.add_argument("--profile", type=int, metavar="N",
                        help="profile System construction + ingredients for snake(N) and exit")
    args = parser.parse_args(argv)
    forms = ("compact", "chain") if args.form == "both" else (args.form,)
    if args.profile:
        profile(args.profile, forms[0])
        return 0
    Ns, runs = args.N, args.runs
    if args.quick:
        Ns, runs = [N for N in Ns if N <= QUICK_MAX_N], 1
    print(f"derive benchmark: {environment()}; median of {runs} run(s), sympy cache "
          f"cleared before every timed run, CPU and wall-clock seconds")
    for form in forms:
        print(f"\n### L written in {form} form\n")
        print(table(measure(Ns, runs, form, with_lm=not args.no_lm)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
