"""Paired whole-command timings: the same ``nhham`` commands in two checkouts.

Each command runs as a whole process (``python -m nhham CMD ...``) alternately in
checkout A and checkout B, in the order A B B A A B B A ... so that a drift of the
machine's load (or of its clock) falls on both sides equally. Each checkout runs its
own code (``PYTHONPATH`` = the checkout) with its own compile cache
(``NHHAM_CACHE=/tmp/nhc-<name of the checkout's folder>``), and every command runs
once in each checkout before the timed runs, so no timed run generates or compiles a
model. Output (stdout, stderr) is discarded; a command that exits non-zero in either
checkout is reported and not timed.

The measure is the CPU time of the child (user + sys, from ``os.wait4``): the machine
this was written on has 2 cores and is shared, so wall time depends on the others'
load; the wall medians are printed beside it. For each pair (one run in A and the
next in B) the ratio B/A of CPU seconds is formed; the table gives the median of those
ratios and their range.

Run (from a checkout, commands quoted, one per argument)::

    python bench/paired.py /work/wt-before /work/wt-after \\
        "classify examples/rolling_disk.toml" "derive examples/rolling_disk.toml"

``--runs N`` sets the number of runs in each checkout (default 7), ``--quick`` is
``--runs 3``. Scene paths are relative to each checkout.
"""

from __future__ import annotations

import argparse
import os
import shlex
import statistics
import subprocess
import sys
import time
from pathlib import Path


def run_once(tree: Path, command: str) -> tuple[int, float, float]:
    """Exit status, CPU seconds (user + sys) and wall seconds of one command in ``tree``."""
    env = dict(os.environ, PYTHONPATH=str(tree), NHHAM_CACHE=f"/tmp/nhc-{tree.name}")
    argv = [sys.executable, "-m", "nhham", *shlex.split(command)]
    start = time.perf_counter()
    child = subprocess.Popen(argv, cwd=tree, env=env, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - start
    child.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
    return child.returncode, usage.ru_utime + usage.ru_stime, wall


def order(runs: int) -> list[int]:
    """0 for A, 1 for B: A B B A A B B A ..., ``runs`` of each."""
    return [(i + (i // 2)) % 2 for i in range(2 * runs)]


def measure(trees: tuple[Path, Path], command: str, runs: int) -> dict | None:
    """The timings of ``command`` in both trees, or None when it fails in one of them."""
    for tree in trees:  # the warm-up: a model generated or compiled here is not timed
        code, _, _ = run_once(tree, command)
        if code != 0:
            print(f"{command!r} exits {code} in {tree}: not timed", file=sys.stderr)
            return None
    cpu: list[list[float]] = [[], []]
    wall: list[list[float]] = [[], []]
    for side in order(runs):
        code, c, w = run_once(trees[side], command)
        if code != 0:
            print(f"{command!r} exits {code} in {trees[side]}: not timed", file=sys.stderr)
            return None
        cpu[side].append(c)
        wall[side].append(w)
    ratios = [b / a for a, b in zip(cpu[0], cpu[1])]  # the i-th run of A with the i-th of B
    return {"cpu": cpu, "wall": wall, "ratios": ratios}


def row(command: str, m: dict) -> str:
    med = statistics.median
    cells = [f"`{command}`", *(f"{med(m['cpu'][s]):.2f}" for s in (0, 1)),
             *(f"{med(m['wall'][s]):.2f}" for s in (0, 1)), f"{med(m['ratios']):.3f}",
             f"{min(m['ratios']):.3f}–{max(m['ratios']):.3f}",
             " ".join(f"{r:.2f}" for r in m["ratios"])]
    return "| " + " | ".join(cells) + " |"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("tree_a", type=Path)
    parser.add_argument("tree_b", type=Path)
    parser.add_argument("commands", nargs="+", help='e.g. "classify examples/rolling_disk.toml"')
    parser.add_argument("--runs", type=int, default=7, help="runs in each tree (default 7)")
    parser.add_argument("--quick", action="store_true", help="3 runs in each tree")
    args = parser.parse_args(argv)
    runs = 3 if args.quick else args.runs
    trees = (args.tree_a.resolve(), args.tree_b.resolve())
    print(f"A = {trees[0]}, B = {trees[1]}; {runs} runs each, order A B B A ..., "
          f"one warm-up each; {os.cpu_count()} cores, shared machine (load "
          f"{os.getloadavg()[0]:.1f}): CPU seconds (user + sys) of the child are the "
          "measure, wall beside it")
    print("| command | A CPU s | B CPU s | A wall s | B wall s | B/A CPU (median of pairs) "
          "| min–max | pairs |")
    print("|---|---|---|---|---|---|---|---|")
    for command in args.commands:
        m = measure(trees, command, runs)
        if m is not None:
            print(row(command, m), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
