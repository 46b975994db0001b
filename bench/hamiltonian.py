"""Benchmark: classification and Lagrangian <-> Hamiltonian cross-check, exact vs sampled.

For every model of :mod:`nhham.models` and the N-link snake (N = 1..8) this times

* ``classify_constraints(system, method=...)`` (M_f from the constraint algorithm in
  exact mode; in sampled mode M_f = M_1 once C is seen to be regular numerically),
* ``cross_check(system, method=...)``,

each in a fresh forked process (cold sympy cache, no sharing between rows) with a
time limit, and writes a Markdown table.

Usage::

    python bench/hamiltonian.py                  # everything; the section of bench/RESULTS.md
    python bench/hamiltonian.py --quick          # small subset, print only
    python bench/hamiltonian.py --limit 120      # seconds per measurement
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import platform
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from nhham import models  # noqa: E402
from nhham.hamiltonian.classification import classify_constraints  # noqa: E402
from nhham.hamiltonian.crosscheck import cross_check  # noqa: E402

HERE = Path(__file__).resolve().parent


def _build(name):
    if name.startswith("snake("):
        return models.snake(int(name[6:-1]))
    return models.MODELS[name]()


def _job(name, what, method, queue):
    system = _build(name)
    start = time.perf_counter()
    if what == "classify":
        c = classify_constraints(system, method=method)
        info = f"{c.second_class}/{c.first_class}"
        used = c.method
    else:
        r = cross_check(system, method=method)
        info = ("agree" if r.agree else "DISAGREE") + f" {r.max_rel_difference:.1e}"
        used = r.method
    queue.put((time.perf_counter() - start, info, used))


def measure(name, what, method, limit):
    """(seconds or None, info) for one measurement in a fresh process."""
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    proc = ctx.Process(target=_job, args=(name, what, method, queue))
    proc.start()
    proc.join(limit)
    if proc.is_alive():
        proc.terminate()
        proc.join()
        return None, f"> {limit:g} s", method
    if proc.exitcode != 0 or queue.empty():
        return None, f"failed (exit {proc.exitcode})", method
    return queue.get()


def fmt(seconds):
    return "—" if seconds is None else f"{seconds:.2f}"


def run(names, limit, skip_exact=()):
    rows = []
    for name in names:
        cells = {}
        for what in ("classify", "cross"):
            for method in ("exact", "sampled"):
                if method == "exact" and name in skip_exact:
                    cells[(what, method)] = (None, "skipped", method)
                    continue
                cells[(what, method)] = measure(name, what, method, limit)
        rows.append((name, cells))
        c = cells
        print(f"{name:26s} classify exact {fmt(c['classify', 'exact'][0]):>8} "
              f"sampled {fmt(c['classify', 'sampled'][0]):>7} | cross exact "
              f"{fmt(c['cross', 'exact'][0]):>8} sampled {fmt(c['cross', 'sampled'][0]):>7} "
              f"| {c['classify', 'exact'][1]} {c['cross', 'sampled'][1]}", flush=True)
    return rows


def table(rows):
    head = ("| system | classify exact (s) | classify sampled (s) | second/first class | "
            "cross-check exact (s) | cross-check sampled (s) | cross-check result |\n"
            "|---|---:|---:|:---:|---:|---:|---|\n")
    lines = []
    for name, c in rows:
        ce, cs = c["classify", "exact"], c["classify", "sampled"]
        xe, xs = c["cross", "exact"], c["cross", "sampled"]
        classes = ce[1] if ce[0] is not None else cs[1]
        ex_note = "" if xe[0] is not None else f" ({xe[1]})"
        ce_note = "" if ce[0] is not None else f" ({ce[1]})"
        xs_used = "" if xs[2] == "sampled" else " (fell back to exact)"
        result = xs[1] if xs[0] is not None else xe[1]
        lines.append(f"| {name} | {fmt(ce[0])}{ce_note} | {fmt(cs[0])} | {classes} | "
                     f"{fmt(xe[0])}{ex_note} | {fmt(xs[0])}{xs_used} | {result} |")
    return head + "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a few systems, print only")
    ap.add_argument("--limit", type=float, default=180.0, help="seconds per measurement")
    ap.add_argument("--out", default=None,
                    help="also write the Markdown section to this file (default: print only)")
    args = ap.parse_args(argv)
    if args.quick:
        names = ["rolling_disk", "pendulum_cartesian", "snake(3)", "snake(8)"]
        skip = {"snake(3)", "snake(8)"}
    else:
        names = list(models.MODELS)
        names.remove("snake")
        names += [f"snake({N})" for N in range(1, 9)]
        # Exact work on the snake needs the symbolic inverse of a q-dependent,
        # non-diagonal W: measured up to N = 2, skipped beyond.
        skip = {f"snake({N})" for N in range(3, 9)}
    start = time.perf_counter()
    rows = run(names, args.limit, skip)
    total = time.perf_counter() - start
    if args.quick:
        print(table(rows))
        return
    machine = (f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
               f"Python {platform.python_version()}, load average at the end "
               f"{os.getloadavg()[0]:.1f}")
    text = RESULTS_TEMPLATE.format(machine=machine, limit=args.limit, table=table(rows),
                                   total=total)
    print(text)
    if args.out:
        Path(args.out).write_text(text)
        print(f"wrote {args.out} ({total:.0f} s)")


RESULTS_TEMPLATE = """# Hamiltonian side: classification and cross-check timings

Produced by `python bench/hamiltonian.py` ({machine}). Each number is one
run in a fresh forked process (cold sympy cache), wall time in seconds, limit {limit:g} s
per measurement; total {total:.0f} s.

* *classify exact*: final constraints from the constraint algorithm, brackets in (q, p),
  decisions on M_f exact where possible (then sampled), first-class combinations as
  expressions. *classify sampled*: M_f = M_1 when C is regular at the samples, bracket
  matrices from the numeric layer (no symbolic Legendre inverse), combinations as numbers.
* *cross-check exact*: the constraint algorithm on TQ and on T*Q, exact identities
  (Leg_* xi_L = X_H o Leg, Leg_* Z = Z^H o Leg, C = C^H o Leg, xi_L(phi) = X_H(phi^H) o Leg,
  Leg^* omega_Q = omega_L, Leg^*{{f, g}} = {{Leg^* f, Leg^* g}}_L) plus the assembled field and
  multipliers at 6 seeded points of M_f. *cross-check sampled*: everything numeric at the
  seeded points (numeric solves with W and C on both sides), stages from the numeric rank of
  C on both sides; when C is singular it falls back to the exact path (noted).
* *second/first class*: number of second- and first-class final constraints.
* *cross-check result*: agreement and the largest relative difference |a - b|/max(1, |a|, |b|)
  (tolerance 1e-9, float64).
* "—" means not measured: skipped (the exact path on the snake for N >= 3 needs the
  symbolic inverse of a 5x5 or larger trigonometric W) or over the limit.

{table}
Target: the N = 8 snake's cross-check in under 10 s on a 2-core machine (sampled path).
"""


if __name__ == "__main__":
    main()
