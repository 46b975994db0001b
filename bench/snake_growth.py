"""The N-link snake's classify against sympy's LagrangesMethod as N grows (issue 48).

For each N the scene is written by ``examples/make_snake.py``; then, each in a fresh
process: ``nhham classify snake_N.toml --json`` (the whole command: imports, scene, the
verdict at the parameter values, classes) and a script that loads the same scene and
forms Lagrange's equations with ``sympy.physics.mechanics.LagrangesMethod`` (imports
included). Wall and CPU seconds of the whole process (the CPU from the kernel's
accounting of the finished child), one run each unless ``--runs``; a side that passes
``--timeout`` seconds is stopped and shown as "> T s".

Usage::

    python bench/snake_growth.py                       # N = 8 16 32 48 64
    python bench/snake_growth.py --sizes 8 16 --runs 3
    python bench/snake_growth.py --plot docs/snake_growth.png   # needs matplotlib
    python bench/snake_growth.py --lm earlier.md   # LagrangesMethod's cells read from
                                                   # an earlier table (nhham's measured)

The table is Markdown (bench/RESULTS.md keeps it with the command that made it).
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))

from classify import LM_SCRIPT, _median_command  # noqa: E402

SIZES = (8, 16, 32, 48, 64)


def measure(sizes, runs, timeout, lm_rows=None) -> list:
    """[(N, nhham (wall, CPU, MB) or None, LagrangesMethod (wall, CPU, MB) or None)];
    with ``lm_rows`` ({N: cell}), LagrangesMethod's side is taken from there."""
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for N in sizes:
            path = Path(tmp) / f"snake_{N}.toml"
            subprocess.run([sys.executable, str(ROOT / "examples" / "make_snake.py"), str(N),
                            str(path)], check=True, capture_output=True)
            nhham = _median_command([sys.executable, "-m", "nhham", "classify", str(path),
                                     "--json"], runs, timeout)
            lm = (lm_rows[N] if lm_rows is not None else
                  _median_command([sys.executable, "-c", LM_SCRIPT, str(path)], runs, timeout))
            rows.append((N, nhham, lm))
            print(_row(rows[-1], timeout), flush=True)
    return rows


def read_lm(path, timeout) -> dict:
    """{N: (wall, CPU, 0) or None} from the LagrangesMethod column of an earlier table."""
    out = {}
    for line in Path(path).read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 5 and cells[0].isdigit():
            lm = cells[3]
            out[int(cells[0])] = None if lm.startswith(">") else (
                *map(float, lm.split(" / ")), 0.0)
    return out


def _cell(res, timeout) -> str:
    return f"> {timeout:g} s" if res is None else f"{res[0]:.2f} / {res[1]:.2f}"


def _row(row, timeout) -> str:
    N, nhham, lm = row
    ratio = "-" if nhham is None or lm is None else f"{lm[1] / nhham[1]:.1f}"
    if nhham is not None and lm is None:
        ratio = f"> {timeout / nhham[1]:.1f}"
    return (f"| {N} | {N + 2} | {_cell(nhham, timeout)} | {_cell(lm, timeout)} | {ratio} |")


def plot(rows, timeout, path) -> None:
    """Log-log CPU seconds of both sides against N; a stopped run drawn at the bound
    with an upward arrow."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for index, (label, marker) in enumerate((("nhham classify (whole command)", "o"),
                                             ("LagrangesMethod: form the equations", "s"))):
        done = [(N, r[1]) for N, *sides in rows if (r := sides[index]) is not None]
        stopped = [N for N, *sides in rows if sides[index] is None]
        if done:
            ax.plot(*zip(*done), marker=marker, label=label)
        if stopped:
            ax.plot(stopped, [timeout] * len(stopped), marker=6, linestyle="none",
                    color=ax.lines[-1].get_color() if done else None,
                    label=f"{label.split(':')[0]}: stopped at {timeout:g} s")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xticks([N for N, *_ in rows], [str(N) for N, *_ in rows])
    ax.set_xlabel("links N (n = N + 2 coordinates, m = N constraints)")
    ax.set_ylabel("CPU seconds, whole process")
    ax.set_title("The N-link snake: classify against LagrangesMethod")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=600.0)
    ap.add_argument("--plot", metavar="PNG")
    ap.add_argument("--lm", metavar="TABLE", help="LagrangesMethod's cells from an earlier "
                    "table of this script (its runs take minutes)")
    args = ap.parse_args(argv)
    load = os.getloadavg()[0]
    print(f"# snake growth: Python {platform.python_version()}, {os.cpu_count()} CPUs, load "
          f"average {load:.1f}; whole processes, median of {args.runs}: wall s / CPU s")
    print("| N | n | nhham classify --json | LagrangesMethod script | LM / nhham (CPU) |")
    print("|---|---|---|---|---|")
    lm_rows = read_lm(args.lm, args.timeout) if args.lm else None
    rows = measure(args.sizes, args.runs, args.timeout, lm_rows)
    if args.plot:
        plot(rows, args.timeout, args.plot)
        print(f"# plot: {args.plot}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
