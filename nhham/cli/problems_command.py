"""``nhham problems``: the published problems, nhham's answers beside the sources'.

No scene: the problems are the package's (:mod:`nhham.problems`). Positional names choose
some (all by default); ``--out DIR`` writes the IFToMM bicycle's results files, ``--plot
FILE`` draws its maneuvers (roll, steer and energy against t, side by side).
"""

from __future__ import annotations

from nhham.errors import UsageError

__all__ = ["PROBLEMS_HELP", "add_parser", "cmd_problems"]

PROBLEMS_HELP = ("published problems: nhham's values beside the sources'",
                 "Run the library of published nonholonomic problems (the benchmark bicycle's "
                 "eigenvalues and speeds, the IFToMM uncontrolled bicycle, closed forms of "
                 "the classical systems, the paper's examples): each quantity's published "
                 "value, nhham's, the relative error, whether it is within the source's "
                 "printed precision, the time and the method.",
                 "nhham problems iftomm_bicycle --out results --plot iftomm.png --coarsest")


def add_parser(sub, epilog, budget_value):
    """The ``problems`` subparser (its own arguments: it reads no scene)."""
    import argparse

    short, long, example = PROBLEMS_HELP
    p = sub.add_parser("problems", help=short, description=long,
                       epilog=f"example: {example}\n{epilog}",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("names", nargs="*", metavar="PROBLEM",
                   help="problems to run (default: all; --list names them)")
    p.add_argument("--list", action="store_true", help="list the problems and their sources")
    p.add_argument("--out", metavar="DIR", default=None,
                   help="write the IFToMM bicycle's results files there (M1.txt, M2.txt, "
                        "M3.txt and bicycleResultsIFToMM.txt)")
    p.add_argument("--coarsest", action="store_true",
                   help="also find the coarsest DOP853 rtol at which every IFToMM maneuver "
                        "meets the library's 1e-3 %% (more runs of the bicycle)")
    p.add_argument("--plot", metavar="FILE", default=None,
                   help="draw the IFToMM maneuvers (roll, steer, energy against t); needs "
                        "the plot extra: pip install 'nhham[plot]'")
    p.add_argument("--json", action="store_true",
                   help="print one JSON envelope {command, nhham_version, scene, result, "
                        "warnings, error}; result.rows: {problem, quantity, source, "
                        "published, value, relative_error, precision, within, time_s, method}")
    p.add_argument("--verbose", action="store_true", help="timings of each step on stderr")
    p.add_argument("--debug", action="store_true", help="tracebacks for internal errors")
    p.add_argument("--budget", type=budget_value, default=None, metavar="SECONDS",
                   help="stop after SECONDS (exit 3); 'none': no bound (default: no bound)")
    return p


def cmd_problems(args, steps):
    from nhham.cli.envelope import CommandOutput
    from nhham.problems import problems, run

    known = {p.name: p for p in problems()}
    unknown = [n for n in args.names if n not in known]
    if unknown:
        raise UsageError(f"no problem {', '.join(map(repr, unknown))}; known: "
                         f"{', '.join(known)}", key="PROBLEM")
    if args.list:
        chosen = [known[n] for n in args.names] if args.names else list(known.values())
        rows = [{"problem": p.name, "title": p.title, "source": p.citation,
                 "checked": p.checked, "quantities": [q.name for q in p.quantities]}
                for p in chosen]
        text = "\n".join(f"{p.name}: {p.title}\n  {p.citation}\n  checked: {p.checked}"
                         for p in chosen)
        return CommandOutput(result={"problems": rows}, text=text)
    report = run(args.names or None, out_dir=args.out, coarsest=args.coarsest, step=steps.step)
    data = report.to_dict()
    if args.plot:
        from nhham.render.plotting import save_figure
        from nhham.problems.plot import plot_maneuvers

        if not report.maneuvers:
            raise UsageError("--plot draws the IFToMM maneuvers: run iftomm_bicycle",
                             key="--plot")
        with steps.step(f"plot {args.plot}"):
            data["plot"] = save_figure(plot_maneuvers(report.maneuvers), args.plot)
    return CommandOutput(result=data, text=report.render())
