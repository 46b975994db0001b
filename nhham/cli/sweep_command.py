"""``nhham sweep SCENE``: a parameter study on a grid or samples, run on Dask.

Usage::

    nhham sweep SCENE --what linearize|simulate|classify --over P=A:B:N [--over Q=...]
                [--samples K [--sampler lhs|sobol|uniform] [--seed S]]
                [--initial-perturbation NAME=SIGMA ...] --out FILE(.zarr|.nc)
                [--resume | --overwrite] [--workers N] [--scheduler ADDRESS]
                [--budget SECONDS] [--plot FILE]

See :func:`nhham.study.sweep.sweep`. JSON (the ``result`` of the envelope, schema
``$defs/sweep``): ``path``, ``points``, ``computed``, ``complete``, ``wall_time_s``,
``run_time_s`` (the chunks alone), ``seconds_per_point`` (of the chunks), ``scheduler``, ``workers``, ``chunks``, ``dims``, ``variables``,
``summary`` (by kind: the stable fraction and the boundaries' range, the runs that
failed, the verdicts' counts) and ``plot``.
"""

from __future__ import annotations


import numpy as np

from nhham.errors import InputError, NhhamError

__all__ = ["add_arguments", "cmd_sweep", "SWEEP_HELP"]

#: (short help, description, example) for ``nhham sweep --help``.
SWEEP_HELP = (
    "parameter studies: grids and samples on Dask",
    "Evaluate the scene at every point of a grid (--over P=START:STOP:COUNT, one dimension "
    "per parameter) or of samples (--samples K over P=START:STOP ranges; "
    "--initial-perturbation for ensembles): the stability of its [steady] motion "
    "(linearize; boundaries located along the first parameter, and along the second on a "
    "grid of two or more), a run from its [initial] "
    "state (simulate) or its constraint-set verdict (classify). Chunks run on Dask, locally "
    "(threads or processes) or on a cluster (--scheduler ADDRESS), and are written to --out (.zarr, or .nc at the end) "
    "as they finish; --resume continues an interrupted study.",
    "nhham sweep examples/whipple_bicycle_benchmark.toml --what linearize "
    "--over v=0:10:201 --over c=0:0.2:101 --out map.zarr --plot map.png")


def add_arguments(parser) -> None:
    """The command's own options (the common ones are added by ``main``)."""
    from nhham.study.kinds import KINDS, SIMULATE_METHODS as METHODS
    from nhham.study.points import SAMPLERS

    parser.add_argument("--what", required=True, choices=tuple(KINDS),
                        help="what to compute at every point: " + "; ".join(
                            f"{k.name}: {k.help}" for k in KINDS.values()))
    parser.add_argument("--over", action="append", default=[], metavar="P=A:B:N",
                        help="a swept parameter (or, for simulate, initial value): a grid "
                             "P=START:STOP:COUNT, a range P=START:STOP (with --samples) or "
                             "values P=A,B,C; repeatable (one dimension each)")
    parser.add_argument("--samples", dest="sample_count", type=int, default=None,
                        metavar="K", help="draw K points in the ranges instead of a grid")
    parser.add_argument("--sampler", choices=SAMPLERS, default="lhs",
                        help="how samples are drawn (default: lhs, Latin hypercube)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the samples (default 0)")
    parser.add_argument("--initial-perturbation", dest="initial_perturbation",
                        action="append", default=[], metavar="NAME=SIGMA",
                        help="simulate with --samples: add a normal perturbation of standard "
                             "deviation SIGMA to an initial value; repeatable")
    parser.add_argument("--out", required=True, metavar="FILE",
                        help="where the results go: a .zarr directory (written chunk by "
                             "chunk) or a .nc file (netCDF, written at the end)")
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--resume", action="store_true",
                       help="continue the interrupted study at --out (same scene, options "
                            "and nhham; chunks whose data are missing are computed again)")
    group.add_argument("--overwrite", action="store_true",
                       help="replace a study nhham wrote at --out (only once the new one is "
                            "complete; anything else there is refused, untouched)")
    parser.add_argument("--workers", type=int, default=None, metavar="N",
                        help="local workers (default: the cores available, at most four per "
                             "core; 1 runs in this process without Dask)")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="threads (the default for linearize and simulate: this "
                             "process's model shared), processes (the default for "
                             "classify), synchronous, or the address of a running dask "
                             "scheduler: tls://host:8786 (certificates from your dask "
                             "configuration) or tcp://host:8786. Security: what the cluster "
                             "sends back is unpickled in this process, so a hostile or "
                             "compromised scheduler runs code here, and on tcp:// the scene "
                             "and options travel in clear text; use only a cluster you trust, "
                             "over tls:// off this machine")
    parser.add_argument("--chunk", type=int, default=None, metavar="POINTS",
                        help="points per task (default: 4096 linearize, 256 simulate and "
                             "classify)")
    parser.add_argument("--along", default=None, metavar="P",
                        help="linearize: the parameter along which stability boundaries are "
                             "located (default: the first --over)")
    parser.add_argument("--method", default=None, choices=METHODS, metavar="METHOD",
                        help="simulate: one of " + ", ".join(METHODS) + " (default: the "
                             "scene's, else DOP853)")
    parser.add_argument("--rtol", type=float, default=None, help="simulate: relative tolerance")
    parser.add_argument("--atol", type=float, default=None, help="simulate: absolute tolerance")
    parser.add_argument("--t-end", dest="t_end", type=float, default=None, metavar="T",
                        help="simulate: the final time (default: the scene's, else 10)")
    parser.add_argument("--plot", metavar="FILE", default=None,
                        help="a figure: the stability map (linearize over two parameters), "
                             "the boundaries or stable range (one), the spread of the end "
                             "states (simulate), the verdicts (classify); needs matplotlib")


def cmd_sweep(args, steps):
    """The command: run the study, summarise it, draw it."""
    from nhham.cli.envelope import CommandOutput, scene_info
    from nhham.study.kinds import KINDS, kind_of
    from nhham.study.sweep import progress_line, sweep

    if args.plot:
        from nhham.study.plots import pyplot

        pyplot()   # fail before the work when the extra is missing
    kind = kind_of(args.what)
    for name in ("method", "rtol", "atol", "t_end"):
        if getattr(args, name) is not None and name not in kind.run_options:
            takers = ", ".join(k.name for k in KINDS.values() if name in k.run_options)
            raise InputError(f"--{name.replace('_', '-')}: only for --what {takers}",
                             key=f"--{name.replace('_', '-')}")
    progress = progress_line() if steps.progress else None
    with steps.step(f"sweep ({args.what}) over "
                    + (", ".join(args.over) or "initial perturbations")):
        try:
            result = sweep(args.scene, args.what, args.over, samples_count=args.sample_count,
                           sampler=args.sampler, seed=args.seed,
                           initial_perturbation=args.initial_perturbation, out=args.out,
                           resume=args.resume, overwrite=args.overwrite,
                           scheduler=args.scheduler, workers=args.workers,
                           budget=args.budget, chunk_points=args.chunk, along=args.along,
                           policy=args.policy, progress=progress,
                           values=getattr(args, "parameter_values", None),
                           run_options={"method": args.method, "rtol": args.rtol,
                                        "atol": args.atol, "t_end": args.t_end})
        except NhhamError:
            _name_the_scene(args)
            raise
    args.loaded_scene = result.scene
    data = result.to_dict()
    module = kind.load()
    data["summary"] = module.summary(result.dataset)
    data["plot"] = None
    if args.plot:
        from nhham.study.plots import plot_study

        with steps.step(f"plot {args.plot}"):
            data["plot"] = plot_study(result.dataset, args.plot)
    warnings = module.summary_warnings(data["summary"])
    failure = None
    if not result.complete:
        done = f"{data['points'] - _missing(result)} of {data['points']} points done"
        failure = (result.stopped if result.stopped not in (None, "budget") else
                   f"{'the --budget ran out' if result.stopped else 'the study stopped'} "
                   f"with {done} (kept in {result.kept}); continue with --resume")
    return CommandOutput(result=data, text=lambda: _text(args, result, data, module),
                         scene=scene_info(result.scene), failure=failure, warnings=warnings)


def _name_the_scene(args) -> None:
    """The scene of a study that failed after loading it, for the envelope (loaded again
    here, on the failure's path only; a scene that does not load names none)."""
    from nhham.system.scene import load_scene

    try:
        args.loaded_scene = load_scene(args.scene, check_initial=False,
                                       values=getattr(args, "parameter_values", None))
    except NhhamError:
        pass


def _missing(result) -> int:
    return int((~np.asarray(result.dataset["done"].values, dtype=bool)).sum())


def _text(args, result, data, module) -> str:
    from nhham.render.text import table

    dims = " x ".join(f"{d} {n}" for d, n in data["dims"].items())
    rows = [("points", f"{data['points']} ({dims})"),
            ("computed now", f"{data['computed']} in {data['wall_time_s']:.2f} s (chunks "
                             f"{data['run_time_s']:.2f} s"
             + (f", {1e6 * data['seconds_per_point']:.0f} us a point)"
                if data["seconds_per_point"] else ")")),
            ("ran on", f"{data['scheduler']} ({data['workers']} worker(s), {data['chunks']} "
                       f"chunks)"),
            ("results", f"{data['path']}" + ("" if result.complete else " (incomplete)"))]
    rows += module.summary_rows(data["summary"])
    if data["plot"]:
        rows.append(("plot", data["plot"]))
    title = result.scene.name or str(args.scene)
    return f"{title}: sweep ({args.what})\n" + table(rows)

