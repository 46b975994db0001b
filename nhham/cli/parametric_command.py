"""``nhham classify --parametric``: the generic verdict and every exceptional case.

Its own module (the command's longest report): the run, the JSON and the text.
"""

from __future__ import annotations

import functools

from nhham.cli.envelope import CommandOutput, scene_info
from nhham.cli.report import expr_text, table
from nhham.errors import InputError

__all__ = ["classify_parametric"]


def classify_parametric(args, steps, scene) -> CommandOutput:
    """classify --parametric: the generic verdict and every exceptional case."""
    from nhham.hamiltonian.classification import classify_constraints
    from nhham.verdict.parametric import parametric_classification

    if args.latex:
        raise InputError("classify --parametric: --latex is not available (use --json or text)")
    positive = [p.strip() for p in (args.positive or "").split(",") if p.strip()]
    with steps.step("verdicts for every parameter value (generic run, exceptional sets, "
                    "one run per case)"):
        pv = parametric_classification(
            scene.system, positive=positive, max_depth=3 if args.depth is None else args.depth,
            policy=args.policy,
            classes=functools.partial(classify_constraints, policy=args.policy))
    # The report forms what the runs left lazy (integrability, classes): a step of its own,
    # so that a budget running out there is named.
    with steps.step("the verdicts' report (integrability and classes of every case)"):
        data = parametric_data(pv)
    title = scene.name or str(args.scene)
    return CommandOutput(result=data, text=functools.partial(parametric_text, title, pv, data),
                         scene=scene_info(scene), warnings=list(pv.warnings))


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
