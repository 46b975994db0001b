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

import functools
import os
import sys
import traceback

from nhham.cli.budget import BudgetExceeded, time_budget
from nhham.cli.envelope import (
    EXIT_NOT_SUCCEEDED,
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
from nhham.cli.options import check_options
from nhham.cli.report import Steps, expr_text, table
from nhham.errors import InputError, NhhamError, OutputUnwritable, UsageError
from nhham.lagrangian.engine import Policy
from nhham.cli.parser import COMMAND_LINE, METHODS, build_parser, unknown_options
from nhham.numerics.methods import DEFAULT_METHOD, FAMILY_OPTIONS, lookup
from nhham.numerics.simulate_options import check_method_options

__all__ = ["main", "build_parser", "COMMANDS", "METHODS"]


def _load(args, steps, drop_redundant=False):
    from nhham.cli.loading import load_for
    from nhham.errors import RedundantConstraintError

    # [initial] is checked by the commands that use it (_initial), not here.
    with steps.step(f"load scene {args.scene}"):
        try:
            scene = load_for(args, check_initial=False, drop_redundant=drop_redundant
                             or getattr(args, "drop_redundant", False))
        except RedundantConstraintError as exc:  # the command's way to drop it
            raise RedundantConstraintError(
                [p.replace(exc.ADVICE, "run with --drop-redundant to drop it")
                 for p in exc.problems]) from None
    args.loaded_scene = scene  # the envelope of a later failure names the scene
    return scene


def _initial(args, steps, scene) -> tuple:
    """(initial state, warnings) of a command that integrates: ``[initial]`` completed
    (the values left out solved, named in a warning) and checked against the constraints,
    unless ``--project-initial`` projects it."""
    with steps.step("initial state: [initial] completed and checked"):
        y0 = scene.checked_initial(project=getattr(args, "project_initial", False))
    if not scene.initial_solved:
        return dict(y0), []
    from nhham.system.initial_solve import solved_text

    return dict(y0), [f"initial: solved from the constraints: "
                      f"{solved_text(y0, scene.initial_solved)}"]


def _title(scene, args) -> str:
    return scene.name or str(args.scene)


def _parser_for(scene):
    """Read an expression string of the output back with the scene's names."""
    from nhham.system.expressions import parse_expression

    names = scene_info(scene)["names"]
    return lambda text: parse_expression(text, names)


def _report_text(args, scene, latex, plain):
    """A command's text report, formed only when it is shown (not under ``--json``).

    ``latex(parse)`` under ``--latex``, ``parse`` reading the output's expressions
    back with the scene's names (:func:`_parser_for`); else ``plain()``.
    """
    if args.latex:
        return lambda: latex(_parser_for(scene))
    return plain


def _policy(args) -> Policy:
    """The settings of every decision the command takes, built once from its options and
    passed down (``--precision``, ``--samples``, ``--budget``; the rest at their
    defaults)."""
    return Policy(precision=getattr(args, "precision", None),
                  samples=getattr(args, "samples", 6), budget=args.budget)


def _at_values(args, steps, scene, classes=None):
    """The classification at the scene's parameter values (a ``ValuesVerdict``).

    Every command answers for the values the user gave: where they satisfy an
    exceptional condition, its ``system`` has the condition substituted.
    """
    from nhham.verdict.values import classification_at_values

    with steps.step("constraint algorithm at the parameter values (stages, ranks, decisions "
                    "at exact points, integrability, exceptional parameter sets)"):
        at = classification_at_values(scene.system, policy=args.policy, classes=classes)
    if at.verdict.status == "invalid":
        raise InputError(f"{args.scene}: at the parameter values {at.verdict.note}")
    return at


def _parameter_case(at) -> tuple:
    """(JSON ``parameter_case``, text note) of a ``ValuesVerdict``."""
    if not at.conditions:
        return None, ""
    data = {"conditions": [expr_text(c) for c in at.conditions],
            "generic": at.generic.to_dict(), "generic_differs": bool(at.differs)}
    where = ", ".join(f"{expr_text(c)} = 0" for c in at.conditions)
    note = (f"\nnote: the parameter values satisfy {where}; the answer above holds there"
            + (f" and differs from the generic one ({at.generic.describe()})"
               if at.differs else " (the generic verdict is the same)"))
    return data, note


def _with_case(out: CommandOutput, at) -> CommandOutput:
    """``out`` with the parameter case of ``at`` (None: no parameter has a value)."""
    import dataclasses

    if at is None:
        out.result["parameter_case"] = None
        return out
    case, note = _parameter_case(at)
    out.result["parameter_case"] = case
    # Values near an exceptional set warn whether or not they fall in one.
    warnings = list(out.warnings) + list(at.warnings)
    if not note:
        return dataclasses.replace(out, warnings=warnings)
    old = out.text
    text = (lambda: out.render_text() + note) if callable(old) else f"{old}{note}"
    return dataclasses.replace(out, text=text, warnings=warnings)


def _at_scene_values(args, steps, scene):
    """``_at_values`` when some parameter has a value, else None (nothing to place)."""
    return _at_values(args, steps, scene) if scene.system.parameter_values else None


# ---------------------------------------------------------------- classify
def cmd_classify(args, steps) -> CommandOutput:
    """The constraint-set verdict at the scene's parameter values (algorithm,
    integrability, classes); with ``--parametric`` the verdict for every value."""
    from nhham.cli.results import classify_data, classify_latex, classify_text, classify_warnings
    from nhham.hamiltonian.classification import classify_constraints
    from nhham.lagrangian.analysis import ConstraintAnalysis

    scene = _load(args, steps, drop_redundant=True)
    if getattr(args, "parametric", False):
        from nhham.cli.parametric_command import classify_parametric

        return classify_parametric(args, steps, scene)
    # The verdict layer calls the Hamiltonian classification directly (no callback
    # into this module): the walk goes down the layers.
    at = _at_values(args, steps, scene,
                    classes=functools.partial(classify_constraints, policy=args.policy))
    analysis, classes = at.verdict.analysis, at.verdict.classes
    assert isinstance(analysis, ConstraintAnalysis)  # a valid verdict carries its analysis
    for stage in analysis.stages:
        for d in stage.decisions:
            steps.note(f"stage {stage.index}: {d.describe()}")
    data = classify_data(analysis, classes)
    data["parameter_case"], note = _parameter_case(at)
    title = _title(scene, args)
    text = _report_text(args, scene, functools.partial(classify_latex, title, data),
                        lambda: classify_text(title, data) + note)
    return CommandOutput(result=data, text=text, scene=scene_info(scene),
                         warnings=classify_warnings(analysis, classes) + list(at.warnings))


# ------------------------------------------------------------------ derive
def cmd_derive(args, steps) -> CommandOutput:
    """The projected field, multipliers, C and energy (Lagrangian or Hamiltonian side)."""
    scene = _load(args, steps)
    if args.side == "lagrangian":
        from nhham.lagrangian.geometry import lagrangian_geometry

        # One geometry for the command: the analysis at the values takes this one.
        lagrangian_geometry(scene.system, precision=args.policy.precision, closed_form=True)
    at = _at_scene_values(args, steps, scene)
    system = scene.system if at is None else at.system
    if args.side == "hamiltonian":
        from nhham.hamiltonian.side import hamiltonian_side

        side = hamiltonian_side(system, precision=args.policy.precision, closed_form=True)
        with steps.step("Legendre map and Hamiltonian H = E_L o Leg^-1"):
            side.energy
        out = _derive_closed_form(args, steps, scene, side, "hamiltonian", side.analysis)
        out.result.update(form="explicit", mass_matrix=None, forcing=None,
                          constraint_jacobian=None, constraint_rhs=None, contact_forces=None)
        return _with_case(_with_forces(out, system, args.latex), at)
    from nhham.lagrangian.analysis import analyze_constraints
    from nhham.lagrangian.geometry import lagrangian_geometry

    # derive forms closed forms only where it decided to (W cheap, or --explicit asked):
    # its --budget bounds them, not the library's size guard.
    G = lagrangian_geometry(system, precision=args.policy.precision, closed_form=True)
    with steps.step("energy E_L"):
        energy = G.energy
    with steps.step("implicit form: W, F, mu and mu a = -(dphi/dq) v"):
        implicit = _implicit_form(G)
    analysis = None if at is None else at.verdict.analysis
    if not (args.explicit or G.closed_form_affordable):
        return _with_case(_with_forces(_with_contacts(
            _derive_implicit(args, steps, scene, G, implicit, energy, analysis), scene),
            system, args.latex), at)

    def algorithm():
        if analysis is not None:
            return analysis
        return analyze_constraints(system, policy=args.policy)

    out = _derive_closed_form(args, steps, scene, G, "lagrangian", algorithm)
    out.result.update(form="explicit", **implicit)
    return _with_case(_with_forces(_with_contacts(out, scene), system, args.latex), at)


def _with_forces(out: CommandOutput, system, latex: bool = False) -> CommandOutput:
    """``out`` with the generalized forces Q (dissipation included) and the inputs: JSON
    ``generalized_forces`` (null without forces) and ``inputs``, and a text section (rows
    of the aligned block with ``latex``); the text names the field P(xi_L + F^v)."""
    import dataclasses

    from nhham.cli import latex as tex
    from nhham.cli.report import expr_text, labelled, paragraph

    out.result["inputs"] = [u.name for u in system.inputs]
    if not system.has_forces:
        out.result["generalized_forces"] = None
        return out
    forces = [expr_text(f) for f in system.generalized_forces]
    out.result["generalized_forces"] = forces
    text = out.text

    def with_section():
        body = text() if callable(text) else text
        if latex:
            rows = [f"Q &= {tex.matrix_latex([[f] for f in system.generalized_forces])}"]
            if system.inputs:
                rows.append(tex.text("inputs: " + ", ".join(u.name for u in system.inputs)))
            head, end = body.rsplit("\\end{aligned}", 1)
            return head.rstrip("\n") + " \\\\\n" + " \\\\\n".join(rows) + \
                "\n\\end{aligned}" + end
        lines = [paragraph("generalized forces Q (in F; d/dt dL/dv - dL/dq = Q - mu^T "
                           "lambda):"),
                 table([(f"Q[{q.name}]", "=", f) for q, f in zip(system.coordinates, forces)])]
        if system.inputs:
            lines.append(labelled("inputs", ", ".join(u.name for u in system.inputs)))
        return body + "\n" + "\n".join(lines)

    return dataclasses.replace(out, text=with_section)


def _with_contacts(out: CommandOutput, scene) -> CommandOutput:
    """``out`` with the scene's contact forces in implicit form (JSON and a text section)."""
    import dataclasses

    from nhham.cli.results import contact_data, contact_text

    data = contact_data(scene.system, scene.contacts)
    out.result["contact_forces"] = data
    if not data or not callable(out.text):
        return out
    base = out.text
    return dataclasses.replace(out, text=lambda: base() + "\n" + contact_text(data))


def _derive_closed_form(args, steps, scene, side, name, algorithm) -> CommandOutput:
    """The closed forms of one side (``LagrangianGeometry`` or ``HamiltonianSide``: the
    same names on both): C, its rank on M_1, and P(xi) with the multipliers when C is
    regular, else the dynamics the constraint algorithm (``algorithm()``) leaves on M_f."""
    system = side.system
    with steps.step("constraint matrix C = Z_i(phi_j)"):
        C = side.constraint_matrix
    with steps.step("rank of C on M_1"):
        rank = side.constraint_rank
    steps.note(f"rank C on M_1: {rank.describe()}")
    free: tuple = ()
    warnings = list(rank.warnings)
    if rank.value == system.m:
        with steps.step("multipliers lambda = -C^{-T} xi(phi) and the projected field"):
            field, multipliers = list(side.projected_field), list(side.multipliers)
    else:
        # C is singular: the dynamics is whatever the constraint algorithm leaves.
        with steps.step("C singular: constraint algorithm for the dynamics on M_f"):
            analysis = algorithm()
        if analysis.dynamics is None:
            raise InputError(f"{args.scene}: the constraints are inconsistent "
                             f"({analysis.inconsistency}); there is no dynamics to derive "
                             f"(run `nhham classify {args.scene}` for the stages)")
        field = list(analysis.dynamics)
        free = analysis.free_multiplier_symbols
        multipliers = [analysis.multipliers.get(s, s) for s in side.multiplier_symbols]
        warnings += list(analysis.warnings)
    return _derive_output(args, steps, scene, name, side.state, field, multipliers, C,
                          side.energy, free, warnings)


def _implicit_form(G) -> dict:
    """The dynamics as W a + mu^T lambda = F, mu a = -(dphi/dq) v (JSON-ready)."""
    from nhham.cli.results import implicit_data

    return implicit_data(G)


def _derive_implicit(args, steps, scene, G, implicit, energy, analysis=None):
    """derive without closed forms: the mass-matrix form and the verdict on M_f
    (``analysis``: the one already run at the parameter values)."""
    from nhham.cli.report import expr_text
    from nhham.cli.results import implicit_latex, implicit_text
    from nhham.lagrangian.analysis import analyze_constraints

    system = G.system
    if analysis is None:
        with steps.step("constraint algorithm at exact points (M_f, free multipliers)"):
            analysis = analyze_constraints(system, policy=args.policy)
    if analysis.status == "inconsistent":
        raise InputError(f"{args.scene}: the constraints are inconsistent "
                         f"({analysis.inconsistency}); there is no dynamics to derive "
                         f"(run `nhham classify {args.scene}` for the stages)")
    primary = set(system.holonomic) | set(system.phi)
    secondary = [c for c in analysis.final_constraints if c not in primary]
    data = {
        "side": "lagrangian", "form": "implicit",
        "state": [s.name for s in system.state],
        "field": None, "multipliers": None, "constraint_matrix": None,
        "energy": expr_text(energy), "energy_name": "E_L",
        "free_multiplier_symbols": [s.name for s in analysis.free_multiplier_symbols],
        **implicit,
        "accelerations": [s.name for s in G.acceleration_symbols],
        "multiplier_symbols": [s.name for s in G.multiplier_symbols],
        "secondary_constraints": [expr_text(c) for c in secondary],
        "status": analysis.status,
        "note": (f"closed forms of P(xi_L), lambda and C need W^-1 of a {system.n} x "
                 f"{system.n} matrix of functions: not formed; --explicit forms them"),
    }
    text = _report_text(args, scene, functools.partial(implicit_latex, data),
                        functools.partial(implicit_text, _title(scene, args), data))
    return CommandOutput(result=data, text=text, scene=scene_info(scene),
                         warnings=list(analysis.warnings))


def _derive_output(args, steps, scene, side, variables, field, multipliers, C, energy, free,
                   warnings):
    from nhham.cli.results import derive_data, derive_latex, derive_text

    with steps.step("display simplification"):
        data = derive_data(side, variables, field, multipliers, C, energy, free)
    text = _report_text(args, scene, functools.partial(derive_latex, data),
                        functools.partial(derive_text, _title(scene, args), data))
    return CommandOutput(result=data, text=text, scene=scene_info(scene), warnings=warnings)


# ----------------------------------------------------------------- compare
def cmd_compare(args, steps) -> CommandOutput:
    """Lagrangian/Hamiltonian cross-check and the Dirac-versus-projected difference."""
    from nhham.cli.results import compare_data, compare_latex, compare_text
    from nhham.hamiltonian.crosscheck import cross_check

    from nhham.hamiltonian.side import hamiltonian_side

    scene = _load(args, steps)
    at = _at_scene_values(args, steps, scene)
    system = scene.system if at is None else at.system
    # One T*Q side for both checks: its numeric layer is built once.
    side = hamiltonian_side(system, precision=args.policy.precision, samples=args.policy.samples,
                            closed_form=True)
    with steps.step("cross-check through the Legendre map"):
        report = cross_check(system, side=side, policy=args.policy)
    dirac = None
    warnings = []
    with steps.step("Dirac-bracket flow of H against the projected field on M_f"):
        try:
            from nhham.hamiltonian.dirac import dirac_vs_projected

            dirac = dirac_vs_projected(system, side=side, policy=args.policy)
        except BudgetExceeded:  # the budget ran out: exit 3, not a warning
            raise
        except NhhamError as exc:
            warnings.append(f"Dirac comparison not available: {one_line(exc)}")
    data = compare_data(report, dirac)
    title = _title(scene, args)
    text = _report_text(args, scene, functools.partial(compare_latex, title, data),
                        functools.partial(compare_text, title, report, dirac))
    failure = None if data["agree"] else (
        "the Lagrangian and Hamiltonian sides disagree (see the checks); please report this "
        "scene as a bug")
    return _with_case(CommandOutput(result=data, text=text, scene=scene_info(scene),
                                    warnings=warnings, failure=failure), at)


# ---------------------------------------------------------------- simulate
def _simulate_options(args, scene):
    """The scene's [simulate] table overridden by the command line, checked."""
    from nhham.system.scene import simulate_option_problem

    opts = scene.simulate.given()
    given = {k: getattr(args, k) for k in ("method", "rtol", "atol", "step", "t_end", "max_step",
                                           "save_every", "max_points")
             if getattr(args, k, None) is not None}
    opts.update(given)
    method = opts.get("method", DEFAULT_METHOD)
    if method not in METHODS:
        raise InputError(f"method {method!r} (from the scene's [simulate] table) is not one of "
                         f"{', '.join(METHODS)}", key="simulate.method")
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
    t_end = opts.pop("t_end", 10.0)
    return t_end, opts


def cmd_simulate(args, steps) -> CommandOutput:
    """Integrate the constrained dynamics from the scene's initial data."""
    from nhham.cli.results import simulation_data, simulation_failure
    from nhham.numerics.integrate import simulate, storage_plan

    scene = _load(args, steps)
    y0, solved = _initial(args, steps, scene)
    t_end, opts = _simulate_options(args, scene)
    system = _closed_loop(scene, args)
    t_span = (0.0, float(t_end))
    if not args.project_initial:   # a force undefined there: say which (exactly)
        from nhham.system.force_checks import check_forces_at

        check_forces_at(system, scene.initial, where="the initial state")
    with capture_warnings() as caught:
        method = opts.get("method", DEFAULT_METHOD)
        plan = storage_plan(scene.system.n, method, opts.get("save_every", 1),
                            opts.get("max_points"))
        with steps.step(f"simulate with {method} ({plan})"):
            result = simulate(system, t_span=t_span, y0=y0,
                              project_initial=args.project_initial, progress=steps.progress,
                              contacts=scene.contacts, **opts)
    data = simulation_data(result, t_span)
    data["contact_forces"] = _contact_forces(result, caught)
    data["output"] = None
    data["plot"] = None
    if args.output:
        with steps.step(f"write {args.output}"):
            data["output"] = str(result.save(args.output))
    if args.plot:
        from nhham.cli.plotting import plot_trajectory, save_figure

        with steps.step(f"plot {args.plot}"):
            fig = plot_trajectory(result, title=f"{_title(scene, args)}: {result.method}")
            data["plot"] = save_figure(fig, args.plot)
    warnings = solved + [w for w in list(result.warnings) + caught
                         if not w.startswith("run stopped")]
    failure = None
    if not result.success:
        free = ()
        found = result.singularity
        if found.part == "C" if found is not None else int(result.status) == -3:
            free = _free_multipliers(system)
        failure = simulation_failure(result, str(args.scene), free)
    def text():  # the warnings go to stderr, one line each
        return "\n".join(line for line in result.describe().splitlines()
                         if not line.lstrip().startswith("warning:"))
    return CommandOutput(result=data, text=text, scene=scene_info(scene),
                         warnings=warnings, failure=failure)


def _closed_loop(scene, args):
    """The scene's system with its inputs given by the [control] laws and ``--control``
    (the command line's replace the scene's)."""
    laws = dict(scene.control)
    given: set = set()
    for item in getattr(args, "control", None) or []:
        name, sep, expr = item.partition("=")
        if not sep or not name.strip() or not expr.strip():
            raise UsageError(f"--control {item!r}: expected U=EXPR (an input and its law)",
                             key="--control")
        if name.strip() in given:
            raise UsageError(f"--control: {name.strip()} is given twice", key="--control")
        given.add(name.strip())
        laws[name.strip()] = expr.strip()
    if not laws:
        return scene.system
    try:
        return scene.system.closed_loop(laws)
    except InputError as exc:
        message = str(exc)
        where = "--control" if getattr(args, "control", None) else "control"
        raise InputError(message, key=where) from None


def _contact_forces(result, warnings):
    """The scene's contact forces along the run (None without ``[contacts]``)."""
    forces = result.contact_forces
    if forces is None:
        return None
    warnings.extend(forces.warnings)
    out = forces.to_dict()
    out.pop("warnings", None)
    return {"t": [float(t) for t in result.t], **out}


def _free_multipliers(system) -> tuple:
    """Names of the free multipliers (for the failure message), or () if unknown."""
    try:
        from nhham.lagrangian.analysis import analyze_constraints

        return tuple(s.name for s in analyze_constraints(system).free_multiplier_symbols)
    except BudgetExceeded:
        raise
    except Exception:  # the message is a hint; never fail while writing it
        return ()


def cmd_bench(args, steps) -> CommandOutput:
    """Work-precision study of the scene's system."""
    from nhham.cli.results import bench_data, bench_failure, bench_failure_data
    from nhham.numerics.status import NumericalFailure
    from nhham.numerics.workprecision import work_precision

    scene = _load(args, steps)
    y0, solved = _initial(args, steps, scene)
    t_end = args.t_end if args.t_end is not None else (scene.simulate.t_end or 10.0)
    study = "work-precision study" + (" (--quick)" if args.quick else "")
    try:
        with capture_warnings() as caught:
            with steps.step(study):
                result = work_precision(_closed_loop(scene, args), y0,
                                        (0.0, t_end),
                                        quick=args.quick, progress=steps.progress,
                                        reference_digits=args.reference_digits)
    except NumericalFailure as exc:  # no reference: nothing to measure against
        return CommandOutput(result=bench_failure_data((0.0, t_end), args),
                             text=f"work-precision: {_title(scene, args)}, t in [0, {t_end:g}]: "
                                  f"nothing measured (no reference solution)",
                             scene=scene_info(scene), warnings=[],
                             failure=bench_failure(exc, str(args.scene)))
    data = bench_data(result)
    data["plot"] = None
    if args.plot:
        from nhham.cli.plotting import plot_work_precision, save_figure

        with steps.step(f"plot {args.plot}"):
            data["plot"] = save_figure(plot_work_precision(result), args.plot)
    return CommandOutput(result=data, text=result.describe, scene=scene_info(scene),
                         warnings=solved + list(caught))


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
        with capture_warnings() as caught, time_budget(alarm, steps):
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
    except OutputUnwritable as exc:  # a full disk: the command ran; what it kept is said
        return run.fail("failed", str(exc), exc.key, prefix="nhham: ", warnings=caught)
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
    error = None if not out.failure else error_info("failed", out.failure)
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
        return EXIT_NOT_SUCCEEDED
    return EXIT_OK
