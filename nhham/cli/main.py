"""The ``nhham`` command: classify, derive, compare, simulate, bench.

Contract (``DESIGN.md`` §3): ``--json`` prints exactly one JSON object on
stdout; exit status 0 on success, 2 on bad input (one line on stderr, no
traceback), 1 on an internal failure (traceback only with ``--debug``), 3 when
``--budget`` ran out (one line: the step that was running, the steps finished).
Each command derives only what its output needs; ``--verbose`` lists what
was derived, how each decision on M_k was made, and how long each step took.
"""

from __future__ import annotations

import argparse
import json
import sys
import traceback

import sympy as sp

from nhham.errors import InputError, NhhamError
from nhham.cli.budget import BudgetExceeded, time_budget
from nhham.cli.report import Steps, display_form, expr_text, json_number, table

__all__ = ["main"]


# ---------------------------------------------------------------- classify
def _load(args, steps, drop_redundant=False):
    from nhham.system.scene import load_scene

    # With --project-initial the initial data are projected later, not refused here.
    check = not getattr(args, "project_initial", False)
    with steps.step(f"load scene {args.scene}"):
        return load_scene(args.scene, check_initial=check, drop_redundant=drop_redundant
                          or getattr(args, "drop_redundant", False))


def cmd_classify(args, steps):
    """The constraint-set verdict: algorithm, integrability, classes."""
    from nhham.lagrangian.algorithm import analyze_constraints
    from nhham.hamiltonian.classification import classify_constraints

    scene = _load(args, steps, drop_redundant=True)
    system = scene.system
    with steps.step("constraint algorithm (stages, ranks, decisions at exact points)"):
        analysis = analyze_constraints(system, precision=args.precision)
    for stage in analysis.stages:
        for d in stage.decisions:
            steps.note(f"stage {stage.index}: {_evidence_text(d)}")
    with steps.step("Frobenius integrability of the constraint distribution"):
        integrable = analysis.integrable
    classes = None
    if analysis.status != "inconsistent":
        with steps.step("Poisson brackets of the final constraints on M_f (T*Q)"):
            classes = classify_constraints(analysis, precision=args.precision)
    data = {
        "name": scene.name,
        "n": system.n,
        "m": system.m,
        "regular": bool(analysis.regular),
        "rank_C": int(analysis.rank_C),
        "status": analysis.status,
        "stages": [{"index": s.index, "constraints": [expr_text(c) for c in s.constraints],
                    "rank": int(s.rank)} for s in analysis.stages],
        "final_constraints": [expr_text(c) for c in analysis.final_constraints],
        "free_multipliers": int(analysis.free_multipliers),
        "free_multiplier_symbols": [s.name for s in analysis.free_multiplier_symbols],
        "redundant": [d.label for d in analysis.dropped],
        "integrable": integrable,
        "first_class": None if classes is None else int(classes.first_class),
        "second_class": None if classes is None else int(classes.second_class),
        "first_class_combinations": [] if classes is None or classes.first_class_combinations
        is None else [expr_text(c) for c in classes.first_class_combinations],
        "inconsistency": analysis.inconsistency,
        "warnings": list(analysis.warnings) + ([] if classes is None else
                                               list(getattr(classes, "warnings", ()))),
    }
    if args.json:
        return data
    lines = [f"{scene.name or args.scene}: n = {system.n} coordinates, "
             f"m = {system.m} velocity constraints"]
    rows = [
        ("C regular on M_1", "yes" if data["regular"] else "no"),
        ("rank C on M_1", f"{data['rank_C']} ({analysis.stages[0].decisions[0].method if analysis.stages and analysis.stages[0].decisions else 'exact'})"),
        ("status", data["status"]),
        ("stages", str(len(data["stages"]))),
        ("free multipliers", f"{data['free_multipliers']}"
         + (f" ({', '.join(data['free_multiplier_symbols'])})" if data["free_multipliers"] else "")),
        ("redundant (dropped)", ", ".join(data["redundant"]) or "none"),
        ("integrable (holonomic)", {True: "yes", False: "no", None: "undecided"}[integrable]),
    ]
    if classes is not None:
        rows += [("first class", str(data["first_class"])),
                 ("second class", str(data["second_class"]))]
    lines.append(table(rows))
    lines.append("stages:")
    stage_rows = []
    for s in analysis.stages:
        for k, c in enumerate(s.constraints):
            stage_rows.append((f"M_{s.index}" if k == 0 else "", s.labels[k] if k < len(s.labels)
                               else "", expr_text(c), f"rank {s.rank}" if k == 0 else ""))
    lines.append(table(stage_rows))
    lines.append("final constraints:")
    lines.append(table([(lab, expr_text(c)) for lab, c in
                        zip(analysis.final_labels, analysis.final_constraints)]))
    if data["first_class_combinations"]:
        lines.append("first-class combinations (in q, p):")
        lines.append(table([(c,) for c in data["first_class_combinations"]]))
    if data["inconsistency"]:
        lines.append(f"inconsistent: {data['inconsistency']}")
    for w in data["warnings"]:
        lines.append(f"warning: {w}")
    return "\n".join(lines)


def _evidence_text(d):
    for attr in ("describe", "summary"):
        if hasattr(d, attr) and callable(getattr(d, attr)):
            return getattr(d, attr)()
    return str(d)


# ------------------------------------------------------------------ derive
def cmd_derive(args, steps):
    """The projected field, multipliers, C and energy (Lagrangian or Hamiltonian side)."""
    scene = _load(args, steps)
    system = scene.system
    if args.side == "hamiltonian":
        return _derive_hamiltonian(args, steps, scene)
    from nhham.lagrangian.geometry import lagrangian_geometry

    G = lagrangian_geometry(system, precision=args.precision)
    with steps.step("energy E_L"):
        energy = G.energy
    with steps.step("implicit form: W, F, mu and mu a = -(dphi/dq) v"):
        implicit = _implicit_form(G)
    if not (args.explicit or G.closed_form_affordable):
        return _derive_implicit(args, steps, scene, G, implicit, energy)
    with steps.step("constraint matrix C = Z_i(phi_j)"):
        C = G.constraint_matrix
    with steps.step("rank of C on M_1"):
        rank = G.constraint_rank
    steps.note(f"rank C on M_1: {rank.describe()}")
    free = ()
    if rank.value == system.m:
        with steps.step("multipliers lambda = -C^{-T} xi_L(phi) and P(xi_L)"):
            field, multipliers = list(G.projected_field), list(G.multipliers)
    else:
        from nhham.lagrangian.algorithm import analyze_constraints

        # C is singular: the dynamics is whatever the constraint algorithm leaves.
        with steps.step("C singular: constraint algorithm for the dynamics on M_f"):
            analysis = analyze_constraints(system, precision=args.precision)
        if analysis.dynamics is None:
            raise InputError(f"{args.scene}: the constraints are inconsistent "
                             f"({analysis.inconsistency}); there is no dynamics to derive")
        field = list(analysis.dynamics)
        free = analysis.free_multiplier_symbols
        multipliers = [analysis.multipliers.get(s, s) for s in G.multiplier_symbols]
    out = _derive_output(args, steps, scene, "lagrangian", system.state, field, multipliers,
                         C, energy, free)
    if args.json:
        out.update(form="explicit", **implicit)
    return out


def _implicit_form(G) -> dict:
    """The dynamics as W a + mu^T lambda = F, mu a = -(dphi/dq) v (JSON-ready)."""
    system = G.system
    rhs = -G.drift if system.m else sp.zeros(0, 1)
    return {
        "mass_matrix": [[expr_text(G.hessian[i, j]) for j in range(system.n)]
                        for i in range(system.n)],
        "forcing": [expr_text(f) for f in G.forcing],
        "constraint_jacobian": [[expr_text(system.mu[i, j]) for j in range(system.n)]
                                for i in range(system.m)],
        "constraint_rhs": [expr_text(r) for r in rhs],
    }


def _derive_implicit(args, steps, scene, G, implicit, energy):
    """derive without closed forms: the mass-matrix form and the verdict on M_f."""
    from nhham.lagrangian.algorithm import analyze_constraints

    system = scene.system
    with steps.step("constraint algorithm at exact points (M_f, free multipliers)"):
        analysis = analyze_constraints(system, precision=args.precision)
    if analysis.status == "inconsistent":
        raise InputError(f"{args.scene}: the constraints are inconsistent "
                         f"({analysis.inconsistency}); there is no dynamics to derive")
    primary = set(system.holonomic) | set(system.phi)
    secondary = [c for c in analysis.final_constraints if c not in primary]
    data = {
        "name": scene.name, "side": "lagrangian", "form": "implicit",
        "state": [s.name for s in system.state],
        "field": None, "multipliers": None, "C": None,
        "energy": expr_text(energy),
        "free_multiplier_symbols": [s.name for s in analysis.free_multiplier_symbols],
        **implicit,
        "accelerations": [s.name for s in G.acceleration_symbols],
        "multiplier_symbols": [s.name for s in G.multiplier_symbols],
        "secondary_constraints": [expr_text(c) for c in secondary],
        "status": analysis.status,
        "note": (f"closed forms of P(xi_L), lambda and C need W^-1 of a {system.n} x "
                 f"{system.n} matrix of functions: not formed; --explicit forms them"),
    }
    if args.json:
        return data
    a = [f"{s}''" for s in (q.name for q in system.coordinates)]
    lines = [f"{scene.name or args.scene}: dynamics in implicit form "
             f"(W a + mu^T lambda = F, mu a = rhs), a = ({', '.join(data['accelerations'])})"]
    lines.append("mass matrix W:")
    lines.append(table(data["mass_matrix"]))
    lines.append("forcing F:")
    lines.append(table([(n, "=", f) for n, f in zip(a, data["forcing"])]))
    if system.m:
        lines.append("constraint rows mu (mu a = rhs):")
        lines.append(table([row + ["|", r] for row, r in zip(data["constraint_jacobian"],
                                                            data["constraint_rhs"])]))
    if secondary:
        lines.append("secondary constraints (M_f):")
        lines.append(table([(c,) for c in data["secondary_constraints"]]))
    if data["free_multiplier_symbols"]:
        lines.append("free multipliers: " + ", ".join(data["free_multiplier_symbols"]))
    lines.append(f"status: {analysis.status}")
    lines.append(f"energy: {data['energy']}")
    lines.append(f"note: {data['note']}")
    return "\n".join(lines)


def _derive_hamiltonian(args, steps, scene):
    from nhham.hamiltonian.side import hamiltonian_side

    system = scene.system
    with steps.step("Legendre map and Hamiltonian H = E_L o Leg^-1"):
        side = hamiltonian_side(system)
        H = side.H
    with steps.step("C^H and the projected Hamiltonian field"):
        C = side.constraint_matrix_H
        field = list(side.projected_field_H)
        multipliers = list(side.multipliers_H)
    return _derive_output(args, steps, scene, "hamiltonian", side.variables, field, multipliers,
                          C, H, ())


def _derive_output(args, steps, scene, side, variables, field, multipliers, C, energy, free):
    """The derive result as JSON data or text, expressions simplified for display."""
    with steps.step("display simplification"):
        field = [display_form(f) for f in field]
        multipliers = [display_form(f) for f in multipliers]
        C = C.applyfunc(display_form)
    state = [s.name for s in variables]
    data = {
        "name": scene.name,
        "side": side,
        "state": state,
        "field": [expr_text(f) for f in field],
        "multipliers": [expr_text(f) for f in multipliers],
        "C": [[expr_text(C[i, j]) for j in range(C.cols)] for i in range(C.rows)],
        "energy": expr_text(energy),
        "free_multiplier_symbols": [s.name for s in free],
    }
    if args.json:
        return data
    return _render_derive(args, scene, data, field, multipliers, C, energy,
                          [f"{n}'" for n in state])


def _render_derive(args, scene, data, field, multipliers, C, energy, lhs):
    import sympy as sp

    if args.latex:
        lines = [r"\begin{aligned}"]
        lines += [rf"\dot{{{sp.latex(sp.Symbol(n))}}} &= {sp.latex(f)} \\"
                  for n, f in zip(data["state"], field)]
        lines += [rf"{sp.latex(sp.Symbol(f'lambda_{i + 1}'))} &= {sp.latex(f)} \\"
                  for i, f in enumerate(multipliers)]
        lines.append(rf"E &= {sp.latex(energy)}")
        lines.append(r"\end{aligned}")
        lines.append(rf"C = {sp.latex(C)}")
        return "\n".join(lines)
    side = "Hamiltonian field on T*Q" if data["side"] == "hamiltonian" else \
        "projected field P(xi_L) on TQ"
    lines = [f"{scene.name or args.scene}: {side}"]
    lines.append(table([(a, "=", t) for a, t in zip(lhs, data["field"])]))
    if data["multipliers"]:
        lines.append("multipliers:")
        lines.append(table([(f"lambda_{i + 1}", "=", t) for i, t in enumerate(data["multipliers"])]))
        lines.append("constraint matrix C:")
        lines.append(table([[t for t in row] for row in data["C"]]))
    if data["free_multiplier_symbols"]:
        lines.append("free multipliers: " + ", ".join(data["free_multiplier_symbols"]))
    lines.append(f"energy: {data['energy']}")
    return "\n".join(lines)


# ----------------------------------------------------------------- compare
def cmd_compare(args, steps):
    """Lagrangian/Hamiltonian cross-check and the Dirac-versus-projected difference."""
    from nhham.hamiltonian.crosscheck import cross_check

    scene = _load(args, steps)
    with steps.step("cross-check through the Legendre map"):
        report = cross_check(scene.system, precision=args.precision, samples=args.samples)
    dirac = None
    with steps.step("Dirac-bracket flow of H against the projected field on M_f"):
        try:
            from nhham.hamiltonian.classification import dirac_vs_projected

            dirac = dirac_vs_projected(scene.system)
        except NhhamError as exc:
            steps.note(f"Dirac comparison not available: {exc}")
    data = dict(report.to_dict())
    data.setdefault("name", scene.name)
    if dirac is not None:
        data["dirac_vs_projected"] = dirac.to_dict() if hasattr(dirac, "to_dict") else str(dirac)
    if args.json:
        return data
    lines = [f"{scene.name or args.scene}: Lagrangian vs Hamiltonian", report.describe()]
    if dirac is not None:
        lines.append(dirac.describe() if hasattr(dirac, "describe") else str(dirac))
    return "\n".join(lines)


# ---------------------------------------------------------------- simulate
def cmd_simulate(args, steps):
    """Integrate the constrained dynamics from the scene's initial data."""
    from nhham.numerics.integrate import simulate

    scene = _load(args, steps)
    if scene.initial is None:
        raise InputError(f"{args.scene}: simulate needs an [initial] table with a value for "
                         f"every coordinate and velocity")
    opts = scene.simulate.given()
    for key in ("method", "rtol", "atol", "step", "t_end", "max_step"):
        value = getattr(args, key)
        if value is not None:
            opts[key] = value
    t_end = opts.pop("t_end", 10.0)
    with steps.step(f"simulate with {opts.get('method', 'default method')}"):
        result = simulate(scene.system, (0.0, t_end), dict(scene.initial),
                          project_initial=args.project_initial, progress=steps.progress, **opts)
    if args.output:
        with steps.step(f"write {args.output}"):
            result.save(args.output)
    if args.plot:
        from nhham.cli.plotting import plot_trajectory

        with steps.step(f"plot {args.plot}"):
            plot_trajectory(result, args.plot)
    if args.json:
        data = {k: _jsonable(v) for k, v in result.summary().items()}
        # The stable keys of the command's contract.
        data.update(status=int(result.status), t_final=json_number(result.t[-1]),
                    y_final=_jsonable(result.y[:, -1]), rhs_evals=int(result.nfev),
                    constraint_residual_max=json_number(result.constraint_residual_max),
                    energy_drift=json_number(result.energy_drift),
                    wall_time_s=json_number(result.wall_time_s))
        return data
    return result.describe()


def cmd_bench(args, steps):
    """Work-precision study of the scene's system."""
    from nhham.cli.plotting import plot_work_precision
    from nhham.numerics.workprecision import work_precision

    scene = _load(args, steps)
    if scene.initial is None:
        raise InputError(f"{args.scene}: bench needs an [initial] table")
    t_end = args.t_end if args.t_end is not None else (scene.simulate.t_end or 10.0)
    with steps.step("work-precision study"):
        result = work_precision(scene.system, dict(scene.initial), (0.0, t_end),
                                quick=args.quick, progress=steps.progress)
    if args.plot:
        with steps.step(f"plot {args.plot}"):
            plot_work_precision(result, args.plot)
    if args.json:
        return {k: _jsonable(v) for k, v in result.to_dict().items()}
    return result.describe()


def _jsonable(value):
    import numpy as np

    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_jsonable(v) for v in (value.tolist() if isinstance(value, np.ndarray) else value)]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return json_number(value)
    return value


# -------------------------------------------------------------------- main
COMMANDS = {
    "classify": cmd_classify,
    "derive": cmd_derive,
    "compare": cmd_compare,
    "simulate": cmd_simulate,
    "bench": cmd_bench,
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="nhham",
        description="Mechanical systems with non-holonomic constraints: classify a scene's "
                    "constraint set, derive its dynamics, compare the Lagrangian and "
                    "Hamiltonian sides, simulate and benchmark.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    helps = {
        "classify": "the constraint-set verdict (stages, ranks, classes)",
        "derive": "the projected field, multipliers, C and energy",
        "compare": "the Lagrangian/Hamiltonian cross-check",
        "simulate": "integrate from the scene's [initial] data",
        "bench": "work-precision study over methods and tolerances",
    }
    for name, text in helps.items():
        p = sub.add_parser(name, help=text, description=text)
        p.add_argument("scene", help="scene file (TOML)")
        p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
        p.add_argument("--verbose", action="store_true",
                       help="list what was derived, how decisions were made, and timings")
        p.add_argument("--debug", action="store_true", help="tracebacks for internal errors")
        p.add_argument("--budget", type=float, default=None, metavar="SECONDS",
                       help="stop after SECONDS and say what was decided so far (exit 3)")
        p.add_argument("--precision", type=int, default=None, metavar="DIGITS",
                       help="decide on M_k with mpmath at DIGITS digits (default float64)")
        if name in ("derive", "compare", "simulate", "bench"):
            p.add_argument("--drop-redundant", action="store_true",
                           help="drop constraints whose one-form is a combination of others")
        if name == "derive":
            p.add_argument("--latex", action="store_true", help="print LaTeX")
            p.add_argument("--side", choices=("lagrangian", "hamiltonian"), default="lagrangian")
            p.add_argument("--explicit", action="store_true",
                           help="form the closed forms P(xi_L), lambda and C (default: only "
                                "when W is diagonal, constant or n <= 3; the implicit "
                                "mass-matrix form otherwise)")
        if name == "compare":
            p.add_argument("--samples", type=int, default=6, help="seeded points of M_f")
        if name in ("simulate", "bench"):
            p.add_argument("--t-end", dest="t_end", type=float, default=None)
            p.add_argument("--plot", metavar="PNG", default=None)
        if name == "simulate":
            p.add_argument("--method", default=None)
            p.add_argument("--rtol", type=float, default=None)
            p.add_argument("--atol", type=float, default=None)
            p.add_argument("--step", type=float, default=None, help="fixed step size")
            p.add_argument("--max-step", dest="max_step", type=float, default=None)
            p.add_argument("--output", metavar="FILE", default=None,
                           help="trajectory as .csv or .npz")
            p.add_argument("--project-initial", action="store_true",
                           help="project initial data onto M_f instead of refusing them")
        if name == "bench":
            p.add_argument("--quick", action="store_true", help="fewer methods and settings")
    return parser


def main(argv=None) -> int:
    """Run the command; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    steps = Steps(progress=sys.stderr.isatty() and not args.json)
    try:
        with time_budget(args.budget, steps):
            out = COMMANDS[args.command](args, steps)
    except BudgetExceeded as exc:
        print(f"nhham: {_one_line(exc)}; finished before it: {steps.decided()}",
              file=sys.stderr)
        return 3
    except InputError as exc:
        print(f"nhham: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("nhham: interrupted", file=sys.stderr)
        return 1
    except Exception as exc:  # internal failure: say so, traceback on request
        if args.debug:
            traceback.print_exc()
        kind = "internal error" if not isinstance(exc, NhhamError) else "failed"
        print(f"nhham: {kind}: {type(exc).__name__}: {_one_line(exc)}"
              + ("" if args.debug else " (run with --debug for a traceback)"), file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps(out, indent=2, allow_nan=False))
    else:
        print(out)
    if args.verbose:
        print(steps.render(), file=sys.stderr)
    return 0


def _one_line(exc) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__
