"""The gallery's work-precision diagram: wall times as medians over whole passes.

``nhham bench`` times each setting as the median of the runs made within about 0.2 s;
on a shared machine a burst of load in that window moves the whole median, and a
tighter tolerance can then come out faster than a looser one (a line that runs backwards
in time). Here the whole study is run ``--passes`` times, one pass after the other, and
each setting's wall time is the median of its passes' medians, so that one window's
load moves one value of the median, not the plotted one. Errors, evaluations and
residuals are the same in every pass (the runs are deterministic); the first pass's are
kept.

Run: ``python bench/work_precision_figure.py examples/chaplygin_sleigh.toml --passes 5
--plot docs/work_precision_sleigh.png`` (the plot extra). It prints, per method, the
settings whose median still came out faster than the looser one before it, with the
spread of their passes: differences within that spread are noise, not a faster run.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import nhham  # noqa: E402
from nhham.render.plotting import plot_work_precision, save_figure  # noqa: E402
from nhham.numerics.codegen import numeric_model  # noqa: E402
from nhham.numerics.workprecision import (WorkPrecisionResult, WorkPrecisionRow,  # noqa: E402
                                          work_precision)


def median_of_passes(results):
    """One WorkPrecisionResult whose wall times are the medians over ``results``' rows
    (matched by method and setting); the other columns from the first."""
    first = results[0]
    times: dict = {}
    for result in results:
        for row in result.rows:
            times.setdefault((row.method, row.setting), []).append(row.wall_time_s)
    rows = tuple(dataclasses.replace(row, wall_time_s=statistics.median(
        times[(row.method, row.setting)])) for row in first.rows)
    return dataclasses.replace(first, rows=rows), times


def load_rows(path):
    """The WorkPrecisionResult (rows only) of a ``--rows`` file."""
    with open(path, encoding="utf-8") as f:
        data = json.load(f)
    rows = tuple(WorkPrecisionRow(**row) for row in data["rows"])
    return WorkPrecisionResult(rows, data["name"], tuple(data["t_span"]), 0, 0.0, 0.0, "")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene")
    parser.add_argument("--passes", type=int, default=5)
    parser.add_argument("--plot", required=True)
    parser.add_argument("--rows", help="also write the rows and every pass's times (JSON)")
    parser.add_argument("--from-rows", help="draw the rows a --rows file holds (no runs)")
    parser.add_argument("--dpi", type=int, default=150)
    args = parser.parse_args(argv)
    if args.passes < 1:
        parser.error("--passes must be at least 1")
    if args.from_rows:
        save_figure(plot_work_precision(load_rows(args.from_rows)), args.plot, dpi=args.dpi)
        return 0
    scene = nhham.load_scene(args.scene)
    t_end = scene.simulate.t_end or 10.0
    target = numeric_model(scene.system)   # compiled once for every pass
    results = []
    for k in range(args.passes):
        print(f"pass {k + 1} of {args.passes} ...", file=sys.stderr, flush=True)
        results.append(work_precision(target, dict(scene.initial), (0.0, t_end)))
    merged, times = median_of_passes(results)
    save_figure(plot_work_precision(merged), args.plot, dpi=args.dpi)
    if args.rows:
        with open(args.rows, "w", encoding="utf-8") as f:
            json.dump({"name": merged.name, "t_span": list(merged.t_span),
                       "rows": [dataclasses.asdict(r) for r in merged.rows],
                       "pass_times": [[m, s, t] for (m, s), t in times.items()]}, f,
                      indent=1, default=float)
    print(f"wrote {args.plot}: {len(merged.rows)} settings, medians of {args.passes} passes")
    for method in merged.methods():
        rows = [r for r in merged.rows if r.method == method and r.status == 0]
        for a, b in zip(rows, rows[1:]):
            if b.wall_time_s < a.wall_time_s:
                spread = times[(b.method, b.setting)]
                print(f"  {method}: {b.setting} {1e3 * b.wall_time_s:.3g} ms < {a.setting} "
                      f"{1e3 * a.wall_time_s:.3g} ms (passes of {b.setting}: "
                      f"{1e3 * min(spread):.3g} .. {1e3 * max(spread):.3g} ms)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
