"""The ``nhham`` command: classify, derive, compare, simulate, bench.

Contract (see :mod:`nhham.cli.envelope` and ``docs/cli.rst``): ``--json``
prints exactly one JSON envelope ``{command, nhham_version, scene, result,
warnings, error}`` on stdout, whatever the exit status. Exit status 0 on success,
1 on an internal failure (traceback only with ``--debug``), 2 on bad input or
usage (one line on stderr; the options are checked by
:func:`nhham.cli.options.check_options` before any work), 3 when the command ran
but its computation did not succeed or ``--budget`` ran out (one line on stderr
saying why and what to do), 130 after Ctrl-C. A failure's envelope has ``error`` = ``{kind,
message, key}`` and, unless the command ran to its end, a null ``result``.
Warnings are one line each: in the envelope with ``--json``, else on stderr.

Each command derives only what its output needs; ``--verbose`` lists what
was derived, how each decision on M_k was made, and how long each step took.
A new subcommand adds a function ``cmd_<name>(args, steps) -> CommandOutput``
to :data:`COMMANDS` and its options in :func:`build_parser`.
"""

from __future__ import annotations

import os
import sys
import traceback

from nhham.cli.budget import BudgetExceeded, time_budget
from nhham.cli.envelope import (
    ERROR_KINDS,
    EXIT_OK,
    CommandOutput,
    FailureReport,
    capture_warnings,
    envelope,
    error_info,
    one_line,
    print_json,
    scene_info,
)
from nhham.cli.linearize_command import cmd_linearize
from nhham.cli.reduce_command import cmd_hamiltonize, cmd_reduce
from nhham.cli.options import check_options
from nhham.render.text import Steps
from nhham.errors import ComputationError, InputError, NhhamError, UsageError
from nhham.progress import reporting
from nhham.lagrangian.engine import Policy
from nhham.cli.parser import COMMAND_LINE, METHODS, build_parser, unknown_options
from nhham.numerics.methods import FAMILY_OPTIONS, lookup
from nhham.numerics.simulate_options import check_method_options

__all__ = ["main", "build_parser", "COMMANDS", "METHODS"]


def _load(args, steps, drop_redundant=False, singular=False):
    from nhham.cli.loading import load_for
    from nhham.errors import RedundantConstraintError

    # [initial] is checked by the commands that use it (_initial), not here.
    with steps.step(f"load scene {args.scene}"):
        try:
            scene = load_for(args, check_initial=False, drop_redundant=drop_redundant
                             or getattr(args, "drop_redundant", False), singular=singular)
        except RedundantConstraintError as exc:  # the command's way to drop it
            raise RedundantConstraintError(
                [p.replace(exc.ADVICE, "run with --drop-redundant to drop it")
                 for p in exc.problems]) from None
    args.loaded_scene = scene  # the envelope of a later failure names the scene
    return scene


def _title(scene, args) -> str:
    return scene.name or str(args.scene)


def _policy(args) -> Policy:
    """The settings of every decision the command takes, built once from its options and
    passed down (``--precision``, ``--samples``, ``--budget``; the rest at their
    defaults)."""
    return Policy(precision=getattr(args, "precision", None),
                  samples=getattr(args, "samples", 6), budget=args.budget)


def _output(args, scene, answer) -> CommandOutput:
    """The command's output of a journey's answer (its LaTeX under ``--latex``)."""
    text = answer.latex_text if getattr(args, "latex", False) else answer.render
    return CommandOutput(result=answer.to_dict(), text=text, scene=scene_info(scene),
                         warnings=list(answer.warnings), failure=answer.failure)


# ---------------------------------------------------------------- classify
def cmd_classify(args, steps) -> CommandOutput:
    """The constraint-set verdict at the scene's parameter values (algorithm,
    integrability, classes); with ``--parametric`` the verdict for every value."""
    from nhham.journeys.verdict import classify, classify_parametric

    scene = _load(args, steps, drop_redundant=True, singular=True)
    if not getattr(args, "parametric", False):
        return _output(args, scene, classify(scene, policy=args.policy, steps=steps))
    if args.latex:
        raise InputError("classify --parametric: --latex is not available (use --json or text)")
    positive = [p.strip() for p in (args.positive or "").split(",") if p.strip()]
    symbolic = None if args.symbolic is None else args.symbolic.split(",")
    return _output(args, scene, classify_parametric(
        scene, policy=args.policy, positive=positive, depth=args.depth, symbolic=symbolic,
        steps=steps))


# ------------------------------------------------------------------ derive
def cmd_derive(args, steps) -> CommandOutput:
    """The projected field, multipliers, C and energy (Lagrangian or Hamiltonian side)."""
    from nhham.journeys.derivation import derive

    # a singular L: --side hamiltonian is the chain's motion, the journey refuses the rest
    scene = _load(args, steps, singular=True)
    return _output(args, scene, derive(scene, side=args.side, explicit=args.explicit,
                                       policy=args.policy, steps=steps))


# ----------------------------------------------------------------- compare
def cmd_compare(args, steps) -> CommandOutput:
    """Lagrangian/Hamiltonian cross-check and the Dirac-versus-projected difference."""
    from nhham.journeys.comparison import compare

    scene = _load(args, steps, singular=True)  # a singular L: the two chains compared
    return _output(args, scene, compare(scene, policy=args.policy, steps=steps))


# ---------------------------------------------------------------- simulate
def _simulate_options(args, scene):
    """The scene's [simulate] table overridden by the command line, checked."""
    from nhham.system.scene import simulate_option_problem

    opts = scene.simulate.given()
    given = {k: getattr(args, k) for k in ("method", "rtol", "atol", "step", "t_end", "max_step",
                                           "save_every", "max_points", "t_eval")
             if getattr(args, k, None) is not None}
    opts.update(given)
    method = opts.get("method", "auto")
    if method not in METHODS:
        raise InputError(f"method {method!r} (from the scene's [simulate] table) is not one of "
                         f"{', '.join(METHODS)}", key="simulate.method")
    if method != "auto" and not lookup(method).needs_reduction:   # the scene's reduction
        for key in ("symmetry", "then"):                            # is for hamiltonized
            opts.pop(key, None)
    if method != "auto":   # auto chooses within the family of the options given
        spec = lookup(method)
        # The library's check, in the command's words; the scene's values of another
        # family's options are left out (the command line's are refused).
        flags = {"projection"} if getattr(args, "projection", False) else set()
        check_method_options(spec, set(given) | flags, available=opts, spelling=COMMAND_LINE)
        other = {k for family in FAMILY_OPTIONS.values() for k in family} - set(spec.options)
        opts = {k: v for k, v in opts.items() if k not in other}
    if "step" in opts:
        where = "--step" if "step" in given else "simulate.step"
        problem = simulate_option_problem("step", opts["step"], opts.get("t_end", 10.0))
        if problem:
            raise (UsageError if "step" in given else InputError)(f"{where}: {problem}",
                                                                   key=where)
    if getattr(args, "projection", False):
        opts["projection"] = True
    for key in ("symmetry", "then"):   # the reduction of method hamiltonized
        if getattr(args, key, None) is not None:
            opts[key] = [s.strip() for s in getattr(args, key).split(",") if s.strip()]
    t_end = opts.pop("t_end", 10.0)
    if getattr(args, "t_eval", None) is not None:
        opts["t_eval"] = output_times(args.t_eval, t_end)
    return t_end, opts


def output_times(text: str, t_end: float):
    """``--t-eval``: ``T0:T1:N`` (N equally spaced times, ends included) or ``T,T,...``,
    as an increasing array within [0, t_end] (UsageError naming ``--t-eval`` otherwise).

    >>> output_times("0:1:5", 10.0)
    array([0.  , 0.25, 0.5 , 0.75, 1.  ])
    >>> output_times("0.5, 2", 10.0)
    array([0.5, 2. ])
    """
    import numpy as np

    def refuse(why):
        raise UsageError(f"--t-eval: {why}, got {text!r}", key="--t-eval")

    try:
        if ":" in text:
            start, stop, count = text.split(":")
            n = int(count)
            if n < 1:
                refuse("N must be at least 1")
            times = np.linspace(float(start), float(stop), n)
        else:
            times = np.array([float(x) for x in text.split(",") if x.strip()])
    except ValueError:
        refuse("expected T0:T1:N or a list T,T,... of numbers")
    if not times.size or not np.all(np.isfinite(times)):
        refuse("expected finite times")
    if np.any(np.diff(times) <= 0):
        refuse("the times must increase")
    if times[0] < 0 or times[-1] > t_end * (1 + 1e-12):
        refuse(f"the times must lie within [0, t_end = {t_end:g}]")
    return times


def cmd_simulate(args, steps) -> CommandOutput:
    """Integrate the constrained dynamics from the scene's initial data."""
    from nhham.journeys.simulation import simulate

    scene = _load(args, steps, singular=True)   # a singular L: the motion on M_f
    t_end, opts = _simulate_options(args, scene)
    if not scene.system.regular_lagrangian:
        for flag, given in (("--plot", args.plot),
                            ("--project-initial", args.project_initial),
                            ("--control", _control_laws(args))):
            if given:
                raise UsageError(f"{flag}: not built for a singular Lagrangian's run (its "
                                 f"state is (q, p) on M_f; --json has the final state)",
                                 key=flag)
    answer = simulate(scene, t_end=t_end, options=opts, project_initial=args.project_initial,
                      control=_control_laws(args), steps=steps)
    data = answer.to_dict()
    data["output"] = None
    data["plot"] = None
    result = answer.payload.get("result")   # None for a singular L: its own "save"
    if args.output:
        with steps.step(f"write {args.output}"):
            data["output"] = str(result.save(args.output) if result is not None
                                 else answer.payload["save"](args.output))
    if args.plot and result is not None:
        from nhham.render.plotting import plot_trajectory, save_figure

        with steps.step(f"plot {args.plot}"):
            fig = plot_trajectory(result, title=f"{_title(scene, args)}: {result.method}")
            data["plot"] = save_figure(fig, args.plot)
    from nhham.numerics.status import Status

    # a Ctrl-C stopped the run: what it computed is printed and written, then exit 130
    kind = ("interrupted" if result is not None and result.status == Status.INTERRUPTED
            else "failed")
    return CommandOutput(result=data, text=answer.render, scene=scene_info(scene),
                         warnings=list(answer.warnings), failure=answer.failure,
                         failure_kind=kind)


def _control_laws(args) -> dict:
    """The ``--control U=EXPR`` laws by input (each input once)."""
    laws: dict = {}
    for item in getattr(args, "control", None) or []:
        name, sep, expr = item.partition("=")
        if not sep or not name.strip() or not expr.strip():
            raise UsageError(f"--control {item!r}: expected U=EXPR (an input and its law)",
                             key="--control")
        if name.strip() in laws:
            raise UsageError(f"--control: {name.strip()} is given twice", key="--control")
        laws[name.strip()] = expr.strip()
    return laws


def cmd_bench(args, steps) -> CommandOutput:
    """Work-precision study of the scene's system."""
    from nhham.journeys.benchmark import bench

    scene = _load(args, steps)
    t_end = args.t_end if args.t_end is not None else (scene.simulate.t_end or 10.0)
    answer = bench(scene, t_end=t_end, quick=args.quick, reference_digits=args.reference_digits,
                   control=_control_laws(args), steps=steps)
    data = answer.to_dict()
    if args.plot and answer.succeeded:
        from nhham.render.plotting import plot_work_precision, save_figure

        with steps.step(f"plot {args.plot}"):
            data["plot"] = save_figure(plot_work_precision(answer.payload["result"]), args.plot)
    return CommandOutput(result=data, text=answer.render, scene=scene_info(scene),
                         warnings=list(answer.warnings), failure=answer.failure)


def cmd_problems(args, steps) -> CommandOutput:
    """The published problems (:mod:`nhham.cli.problems_command`, imported when it runs)."""
    from nhham.cli.problems_command import cmd_problems as run

    return run(args, steps)


def cmd_sweep(args, steps) -> CommandOutput:
    """A parameter study (:mod:`nhham.cli.sweep_command`, imported when it runs)."""
    from nhham.cli.sweep_command import cmd_sweep as run

    return run(args, steps)


# -------------------------------------------------------------------- main
COMMANDS = {
    "classify": cmd_classify,
    "derive": cmd_derive,
    "compare": cmd_compare,
    "simulate": cmd_simulate,
    "bench": cmd_bench,
    "linearize": cmd_linearize,
    "sweep": cmd_sweep,
    "reduce": cmd_reduce,
    "hamiltonize": cmd_hamiltonize,
    "problems": cmd_problems,
}


def main(argv=None) -> int:
    """Run the command; returns the exit status."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv == ["--version"]:   # needs no parser (whose commands import numpy)
        from nhham.settings import __version__

        print(f"nhham {__version__}")
        return EXIT_OK
    parser = build_parser()
    words = [a for a in argv if a in COMMANDS]
    # Where failures are reported, as far as the command line was understood.
    run = FailureReport(command=words[0] if words else None, json="--json" in argv)
    try:
        args, extra = parser.parse_known_args(argv)
        # Once the scene has loaded (_load), a failure's envelope names it.
        run = FailureReport(command=args.command, json=args.json,
                            scene=lambda: getattr(args, "loaded_scene", None))
        if extra:
            raise UsageError(f"{unknown_options(parser, args.command, extra)} "
                             f"(see `nhham {args.command} --help`)",
                             key=next((e.split("=")[0] for e in extra if e.startswith("-")),
                                      None))
        check_options(args)
    except UsageError as exc:
        prefix = f"nhham {run.command}: error: " if run.command else "nhham: error: "
        return run.fail("usage", str(exc), exc.key, prefix=prefix)
    steps = Steps(progress=sys.stderr.isatty() and not run.json)
    try:
        args.policy = _policy(args)
        # sweep keeps to its --budget itself: what finished is kept and reported
        alarm = None if args.command == "sweep" else args.policy.budget
        with capture_warnings() as caught, time_budget(alarm, steps), reporting(steps):
            out = COMMANDS[args.command](args, steps)
            if not isinstance(out, CommandOutput):  # a plain dict (JSON) or text
                out = CommandOutput(result=out if isinstance(out, dict) else {},
                                    text=out if isinstance(out, str) else "")
            if not run.json:
                with steps.step("write the text report"):
                    text = out.render_text()
            else:
                text = None
    except BudgetExceeded as exc:
        return run.fail("budget", f"{exc}; finished before it: {steps.decided()}; allow more "
                                  f"with a larger --budget (or --budget none)", prefix="nhham: ",
                        warnings=caught)
    except InputError as exc:
        return run.fail("usage" if isinstance(exc, UsageError) else "input", str(exc), exc.key,
                        warnings=caught)
    except ComputationError as exc:  # did not succeed (not the input's fault): why, what to do
        return run.fail("computation", str(exc), exc.key, prefix="nhham: ", warnings=caught)
    except KeyboardInterrupt:
        return run.fail("interrupted", "interrupted", prefix="nhham: ", warnings=caught)
    except Exception as exc:  # internal failure: say so, traceback on request
        if args.debug:
            traceback.print_exc()
        kind = "internal error" if not isinstance(exc, NhhamError) else "failed"
        return run.fail("internal", f"{type(exc).__name__}: {exc}"
                        + ("" if args.debug else " (run with --debug for a traceback)"),
                        prefix=f"nhham: {kind}: ", warnings=caught)
    warnings = list(out.warnings) + [w for w in caught if w not in out.warnings]
    if getattr(args, "parameter_values", None):  # the values this run used, said once
        warnings.insert(0, "--set: " + ", ".join(f"{k} = {v:g}" for k, v in
                                                 args.parameter_values.items())
                        + " for this run (instead of the scene's values)")
    try:
        return _print_output(args, out, text, warnings, steps)
    except BrokenPipeError:  # the reader stopped early (| head): not an error of ours
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK


def _print_output(args, out, text, warnings, steps) -> int:
    error = None if not out.failure else error_info(out.failure_kind, out.failure)
    if getattr(args, "json", False):
        print_json(envelope(args.command, out.result, scene=out.scene, warnings=warnings,
                            error=error))
    else:
        print(text)
        for w in dict.fromkeys(one_line(w) for w in warnings):
            print(f"nhham: warning: {w}", file=sys.stderr)
    if getattr(args, "verbose", False):
        print(steps.render(), file=sys.stderr)
    if out.failure:
        print(f"nhham: {one_line(out.failure)}", file=sys.stderr)
        return ERROR_KINDS[out.failure_kind]
    return EXIT_OK
