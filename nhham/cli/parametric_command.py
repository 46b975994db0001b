"""``nhham classify --parametric``: the generic verdict and every exceptional case.

Its own module (the command's longest report): the run, the JSON and the text.
"""

from __future__ import annotations

import functools

from nhham.cli.envelope import CommandOutput, scene_info
from nhham.cli.report import expr_text, table
from nhham.errors import InputError, UsageError

__all__ = ["classify_parametric"]


def classify_parametric(args, steps, scene) -> CommandOutput:
    """classify --parametric: the generic verdict and every exceptional case."""
    from nhham.hamiltonian.classification import classify_constraints
    from nhham.verdict.parametric import parametric_classification

    if args.latex:
        raise InputError("classify --parametric: --latex is not available (use --json or text)")
    positive = [p.strip() for p in (args.positive or "").split(",") if p.strip()]
    symbolic = symbolic_names(scene.system, getattr(args, "symbolic", None))
    with steps.step("verdicts for every parameter value (generic run, exceptional sets, "
                    "one run per case)"):
        pv = parametric_classification(
            scene.system, positive=positive, max_depth=3 if args.depth is None else args.depth,
            policy=args.policy, symbolic=symbolic, progress=steps.part,
            classes=functools.partial(classify_constraints, policy=args.policy))
    # The report forms what the runs left lazy (integrability, classes): a step of its own,
    # so that a budget running out there is named.
    with steps.step("the verdicts' report (integrability and classes of every case)"):
        data = parametric_data(pv)
    title = scene.name or str(args.scene)
    return CommandOutput(result=data, text=functools.partial(parametric_text, title, pv, data),
                         scene=scene_info(scene), warnings=list(pv.warnings))


def symbolic_names(system, text: str | None) -> list:
    """The parameters ``--symbolic`` keeps symbolic (names).

    None (not given): :func:`~nhham.verdict.parametric.classifying_parameters`, and every
    parameter without a value (it cannot be held); ``all``: every parameter.

    Raises
    ------
    UsageError
        A name that is not a parameter (key ``--symbolic``), with the closest one.
    """
    import difflib

    from nhham.verdict.parametric import classifying_parameters

    params = [p.name for p in system.declared_parameters]
    if text is None:
        keep = set(classifying_parameters(system))
        return [p.name for p in system.declared_parameters
                if p in keep or p not in system.parameter_values]
    names = [n.strip() for n in text.split(",") if n.strip()]
    if names == ["all"]:
        return params
    for n in names:
        if n not in params:
            close = difflib.get_close_matches(n, params, n=1)
            raise UsageError(f"--symbolic: {n!r} is not a parameter of the scene"
                             + (f"; did you mean {close[0]!r}?" if close else
                                f" (parameters: {', '.join(params) or 'none'})"),
                             key="--symbolic")
    return names


def _verdict_data(v) -> dict:
    from nhham.cli.results import classify_data

    if v.status == "invalid":
        return {"status": "invalid", "note": v.note}
    out = classify_data(v.analysis, v.classes)
    out["note"] = None
    return out


def parametric_data(pv) -> dict:
    """The JSON result of a ``ParametricVerdict``."""
    return {
        "parameters": [p.name for p in pv.parameters],
        "positive": [p.name for p in pv.positive],
        "values": {p.name: float(v) for p, v in pv.values.items()},
        "held": {p.name: float(v) for p, v in pv.held.items()},
        "generic": _verdict_data(pv.generic),
        "cases": [{"conditions": [expr_text(c) for c in case.conditions],
                   "excluding": [expr_text(c) for c in case.excluding],
                   "reasons": list(case.reasons),
                   "verdict": _verdict_data(case.verdict)} for case in pv.cases],
        "scene_case": pv.scene_case,
        "dropped": [{"conditions": [expr_text(c) for c in eqs], "reason": why}
                    for eqs, why in pv.dropped],
        "notes": list(pv.notes),
    }


def parametric_text(title: str, pv, data: dict) -> str:
    """The text report of a ``ParametricVerdict`` (``data``: its :func:`parametric_data`)."""
    names = ", ".join(data["parameters"]) or "(none)"
    pos = ", ".join(data["positive"])
    lines = [f"{title}: verdicts for every value of the parameters {names}"
             + (f" (declared positive: {pos})" if pos else "")]
    if data["held"]:
        lines.append("held at their values: " + ", ".join(
            f"{k} = {v:g}" for k, v in data["held"].items())
            + " (--symbolic NAMES keeps others symbolic; --symbolic all every one)")
    lines.append("generic (where no case below holds):")
    lines.append(table([("verdict", pv.generic.describe())]))
    for i, case in enumerate(pv.cases):
        lines.append(f"case {i}: " + " and ".join(
            f"{c} = 0" for c in data["cases"][i]["conditions"]))
        rows = []
        if case.excluding:
            rows.append(("excluding", ", ".join(
                f"{c} = 0" for c in data["cases"][i]["excluding"])))
        rows.append(("verdict", case.verdict.describe()))
        diff = case.verdict.differences(pv.generic)
        if diff and case.verdict.status != "invalid":
            rows.append(("differs in", ", ".join(diff)))
        rows.append(("why", "; ".join(case.reasons)))
        lines.append(table(rows))
    if pv.dropped:
        lines.append("dropped (no real solution with the declared signs):")
        lines.append(table([(", ".join(f"{c} = 0" for c in d["conditions"]), d["reason"])
                            for d in data["dropped"]]))
    if data["values"]:
        where = "generic" if pv.scene_case is None else f"case {pv.scene_case}"
        lines.append("scene values " + ", ".join(
            f"{k} = {v}" for k, v in data["values"].items()) + f": {where}")
    lines += [f"note: {n}" for n in data["notes"]]
    return "\n".join(lines)
