"""The command line: every command's options, their help, and usage errors.

Built once by :func:`build_parser`; a usage error is a one-line
:class:`~nhham.errors.UsageError` (exit status 2) naming the option.
"""

from __future__ import annotations

import argparse

from nhham.cli.envelope import (
    one_line,
)
from nhham.cli.options import DEFAULT_BUDGET, argparse_key, budget_value
from nhham.errors import UsageError
from nhham.numerics.methods import names
from nhham.numerics.simulate_options import Spelling

__all__ = ["METHODS", "FIXED_STEP", "COMMAND_LINE", "build_parser", "add_common_arguments", "unknown_options"]


#: Integration methods of ``nhham simulate`` (those of :func:`nhham.simulate`: the
#: registry :data:`nhham.numerics.methods.METHODS`, and ``auto``:
#: :mod:`nhham.numerics.method_choice`).
METHODS = names() + ("auto",)


FIXED_STEP = names(lambda m: m.fixed_step)


def _option(key: str) -> str:
    return "--" + key.replace("_", "-")


#: How ``simulate``'s options are written on the command line, for the library's checks
#: (:func:`nhham.numerics.simulate_options.check_method_options`): ``--step 0.01``.
COMMAND_LINE = Spelling(key=_option, assign=lambda k, v: f"{_option(k)} {v}", method=str,
                        error=UsageError)


_HELP = {
    "classify": ("the constraint-set verdict (stages, ranks, classes)",
                 "Run the constraint algorithm (stages M_k, rank of C, free multipliers, "
                 "inconsistency), test integrability and sort the final constraints into "
                 "first and second class on T*Q.",
                 "nhham classify examples/paper_3_2.toml"),
    "derive": ("the projected field, multipliers, C and energy",
               "Derive the constrained dynamics: the projected field P(xi_L) on TQ (or, with "
               "--side hamiltonian, the projected Hamiltonian field on T*Q), the multipliers "
               "lambda_i, the constraint matrix C and the energy E_L (or H).",
               "nhham derive examples/rolling_disk.toml --latex"),
    "compare": ("the Lagrangian/Hamiltonian cross-check",
                "Cross-check both sides through the Legendre map (fields, multipliers, "
                "symplectic forms, brackets, stages) and compare the Dirac-bracket flow of H "
                "with the true projected dynamics on M_f.",
                "nhham compare examples/chaplygin_sleigh.toml --json"),
    "simulate": ("integrate from the scene's [initial] data",
                 "Integrate the projected field from the scene's [initial] data; options "
                 "default to the scene's [simulate] table, then to the values shown.",
                 "nhham simulate examples/rolling_disk.toml --method rattle --step 0.01 "
                 "--plot disk.png"),
    "bench": ("work-precision study over methods and tolerances",
              "Measure every method against a high-precision mpmath reference: error at "
              "t_end against wall time, constraint residual and energy drift.",
              "nhham bench examples/chaplygin_sleigh.toml --quick --plot wp.png"),
    # linearize and sweep: their modules' (imported when the parser is built)
}


_EXIT_TEXT = ("exit status: 0 success; 1 internal failure; 2 bad input or usage; 3 the "
              "computation did not succeed (one line on stderr says why and what to do); "
              "130 interrupted (Ctrl-C)")


class _Parser(argparse.ArgumentParser):
    """Usage errors as a :class:`UsageError` (one line, exit status 2), pointing to --help."""

    def error(self, message):
        raise UsageError(f"{one_line(message)} (see `{self.prog} --help`)",
                         key=argparse_key(message))


def build_parser() -> argparse.ArgumentParser:
    """The command line: one subparser a command, its options added by command."""
    from nhham.settings import __version__

    parser = _Parser(
        prog="nhham",
        description="Mechanical systems with non-holonomic constraints: classify a scene's "
                    "constraint set, derive its dynamics, compare the Lagrangian and "
                    "Hamiltonian sides, simulate and benchmark.",
        epilog=_EXIT_TEXT + ". Run `nhham COMMAND --help` for a command's options.")
    parser.add_argument("--version", action="version", version=f"nhham {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    from nhham.cli import linearize_command, reduce_command, sweep_command

    helps = dict(_HELP, linearize=linearize_command.LINEARIZE_HELP,
                 sweep=sweep_command.SWEEP_HELP, reduce=reduce_command.REDUCE_HELP,
                 hamiltonize=reduce_command.HAMILTONIZE_HELP)
    options = dict(_OPTIONS, linearize=linearize_command.add_arguments,
                   sweep=sweep_command.add_arguments, reduce=reduce_command.add_arguments,
                   hamiltonize=reduce_command.add_arguments)
    for name, (short, long, example) in helps.items():
        p = sub.add_parser(name, help=short, description=long,
                           epilog=f"example: {example}\n{_EXIT_TEXT}",
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        add_common_arguments(p, budget=None if name in ("simulate", "bench", "sweep")
                             else DEFAULT_BUDGET)
        _add_shared_options(p, name)
        p.add_argument("--set", action="append", default=[], dest="set_values",
                       metavar="NAME=VALUE",
                       help="give the parameter NAME the value VALUE for this run (a "
                            "number as a scene writes one; repeatable); the JSON's "
                            "scene.parameters has the values used"
                            + ("; a study's every point has it (a name cannot be both "
                               "--set and swept by --over)" if name == "sweep" else ""))
        if name in options:
            options[name](p)
    from nhham.cli.problems_command import add_parser

    add_parser(sub, _EXIT_TEXT, budget_value)   # reads no scene: its own arguments
    return parser


def _add_shared_options(p, name) -> None:
    """Options that several commands take."""
    if name in ("classify", "derive", "compare"):
        p.add_argument("--precision", type=int, default=None, metavar="DIGITS",
                       help="decide ranks and vanishings that need sampling with mpmath at "
                            "DIGITS digits (default: float64)")
        p.add_argument("--latex", action="store_true",
                       help="print LaTeX in the paper's notation instead of text")
    if name in ("derive", "compare", "simulate", "bench"):
        p.add_argument("--drop-redundant", action="store_true",
                       help="drop constraints whose one-form is a combination of the others "
                            "(default: refuse them; classify always drops and reports them)")
    if name in ("simulate", "bench"):
        p.add_argument("--t-end", dest="t_end", type=float, default=None, metavar="T",
                       help="final time (default: the scene's [simulate] t_end, else 10)")
        p.add_argument("--plot", metavar="FILE", default=None,
                       help="save a figure (.png, .pdf, .svg); needs the plot extra: "
                            "pip install 'nhham[plot]'")
        p.add_argument("--control", action="append", default=[], metavar="U=EXPR",
                       help="a control law for the input U: an expression in t, the "
                            "coordinates, velocities and parameters (replaces the scene's "
                            "[control] entry; repeatable)")


def _add_classify_options(p) -> None:
    """classify: --parametric and its options."""
    p.add_argument("--parametric", action="store_true",
                   help="the verdict for generic parameters and every case (parameter "
                        "values given by polynomial equations) where it changes, with "
                        "the case the scene's values fall in; the generic verdict comes "
                        "first, and a search for cases the --budget cuts leaves the cases "
                        "found, with a warning naming what was cut (exit 0)")
    p.add_argument("--positive", default=None, metavar="NAMES",
                   help="with --parametric: comma-separated parameters declared "
                        "positive; conditions without a real solution are dropped")
    p.add_argument("--depth", type=int, default=None, metavar="N",
                   help="with --parametric: bound on the nesting of cases (default: 3)")
    p.add_argument("--symbolic", default=None, metavar="NAMES",
                   help="with --parametric: comma-separated parameters kept symbolic, the "
                        "others held at the scene's values ('all': every one); default: "
                        "those in L and the constraints, the ones that can change the "
                        "verdict where C is regular, and those in the forces or the "
                        "dissipation where C is singular in a verdict found (the runs "
                        "again with them, when the --budget leaves the time; else a "
                        "warning with the estimate); never those only in control laws")


def _add_derive_options(p) -> None:
    """derive: the side and the explicit form."""
    p.add_argument("--side", choices=("lagrangian", "hamiltonian"), default="lagrangian",
                   help="TQ with (q, v) or T*Q with (q, p) (default: lagrangian)")
    p.add_argument("--explicit", action="store_true",
                   help="form the closed forms P(xi_L), lambda and C (default: only "
                        "when W is diagonal, constant or n <= 3; the implicit "
                        "mass-matrix form otherwise)")


def _add_compare_options(p) -> None:
    """compare: the sample points."""
    p.add_argument("--samples", type=int, default=6, metavar="K",
                   help="seeded points of M_f for sampled checks (default: 6)")


def _listed(words) -> str:
    """``a, b and c``."""
    return " and ".join([", ".join(words[:-1]), words[-1]] if len(words) > 1 else words)


def _add_simulate_options(p) -> None:
    """simulate: method, tolerances, steps, output and memory."""
    p.add_argument("--method", default=None, choices=METHODS, metavar="METHOD",
                   help="one of " + ", ".join(METHODS) + " (default: the scene's, else "
                        f"auto: chosen from the system, the reason printed); "
                        f"{_listed(FIXED_STEP)} need --step")
    p.add_argument("--rtol", type=float, default=None,
                   help="relative tolerance of adaptive methods (default: scene's, else "
                        "1e-9)")
    p.add_argument("--atol", type=float, default=None,
                   help="absolute tolerance of adaptive methods (default: scene's, else "
                        "1e-12)")
    p.add_argument("--step", type=float, default=None, metavar="DT",
                   help="step size of the fixed-step methods " + ", ".join(FIXED_STEP))
    p.add_argument("--max-step", dest="max_step", type=float, default=None, metavar="DT",
                   help="largest step of adaptive methods (default: unbounded)")
    p.add_argument("--projection", action="store_true",
                   help="project onto the constraints after every step (adaptive "
                        "methods and "
                        + _listed(names(lambda m: m.takes_projection and not m.adaptive))
                        + "): residual at round-off for a small cost")
    p.add_argument("--output", metavar="FILE", default=None,
                   help="write the trajectory (the kept states): .npz (numpy) or "
                        "otherwise CSV")
    p.add_argument("--t-eval", dest="t_eval", default=None, metavar="T0:T1:N|T,T,...",
                   help="the times at which states are output: N equally spaced from T0 to T1, "
                        "or a list (adaptive methods; within [0, t_end], increasing); e.g. "
                        "--t-eval 0:10:101")
    p.add_argument("--save-every", dest="save_every", type=int, default=None,
                   metavar="J", help="keep every J-th step and the last (default: 1)")
    p.add_argument("--max-points", dest="max_points", type=int, default=None,
                   metavar="K",
                   help="most states kept in memory; beyond it every other one is "
                        "dropped and the stride doubles (default: as many as fit in "
                        "64 MiB, 8 (2n + 2) bytes a state)")
    p.add_argument("--project-initial", action="store_true",
                   help="project [initial] data that violate the constraints onto "
                        "M_1 (the constraints as given, velocity and holonomic) "
                        "instead of refusing them; the result says by how much")
    p.add_argument("--symmetry", default=None, metavar="S1,S2",
                   help="method hamiltonized: the reduction's symmetry coordinates, as "
                        "hamiltonize takes them (default: found among the cyclic ones)")
    p.add_argument("--then", default=None, metavar="C1,C2",
                   help="method hamiltonized: a second reduction step, as hamiltonize "
                        "takes it (e.g. the rubber ball's --symmetry x,y --then yaw)")


def _add_bench_options(p) -> None:
    """bench: the quick set and the reference."""
    p.add_argument("--quick", action="store_true",
                   help="fewer methods and settings (seconds instead of minutes)")
    p.add_argument("--reference-digits", dest="reference_digits", type=int, default=30,
                   metavar="DIGITS",
                   help="digits of the mpmath reference solution (default: 30)")


_OPTIONS = {
    "classify": _add_classify_options,
    "derive": _add_derive_options,
    "compare": _add_compare_options,
    "simulate": _add_simulate_options,
    "bench": _add_bench_options,
}


def unknown_options(parser, command, extra) -> str:
    """Name the options ``command`` does not take, and which commands do."""
    subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    words = []
    after_option = False
    for item in extra:
        opt = item.split("=")[0]
        if not opt.startswith("-"):
            if not after_option:  # a value of the unknown option before it is no news
                words.append(f"unexpected argument {item!r}")
            after_option = False
            continue
        after_option = True
        having = [name for name, p in subparsers.choices.items()
                  if opt in p._option_string_actions]
        words.append(f"{command} has no option {opt}" + (
            f" (it is an option of {', '.join(having)})" if having else ""))
    return "; ".join(dict.fromkeys(words))


def add_common_arguments(p: argparse.ArgumentParser, budget: float | None = None) -> None:
    """The arguments every subcommand has (for new subcommands too).

    ``budget``: the default ``--budget`` in seconds (None: no bound); symbolic work
    has one, so that no input keeps the command busy without end.
    """
    p.add_argument("scene", help="scene file (TOML); see examples/")
    p.add_argument("--json", action="store_true",
                   help="print one JSON envelope {command, nhham_version, scene, result, "
                        "warnings, error} on stdout, whatever the exit status (error: null "
                        "on success, else {kind, message, key})")
    p.add_argument("--verbose", action="store_true",
                   help="list on stderr what was derived, how decisions were made, and timings")
    p.add_argument("--debug", action="store_true", help="tracebacks for internal errors")
    p.add_argument("--budget", type=budget_value, default=budget, metavar="SECONDS",
                   help="stop after SECONDS and say what was decided so far (exit 3); "
                        "'none': no bound (default: "
                        + ("no bound" if budget is None else f"{budget:g}") + ")")
