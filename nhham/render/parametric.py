"""The report of a :class:`~nhham.verdict.results.ParametricVerdict` (``nhham classify
--parametric``): its JSON result and its text."""

from __future__ import annotations

from nhham.render.text import expr_text, paragraph, table

__all__ = ["parametric_data", "parametric_text", "search_data"]


def _verdict_data(v) -> dict:
    from nhham.render.results import classify_data

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
        "search": search_data(pv.search),
    }


def search_data(report) -> dict:
    """The JSON form of a :class:`~nhham.verdict.results.SearchReport`."""
    return {"complete": report.complete, "seconds": round(report.seconds, 3),
            "allowed_s": None if report.allowed is None else round(report.allowed, 3),
            "cut": [{"search": what, "why": why} for what, why in report.cut],
            "pending": [[expr_text(e) for e in eqs] for eqs in report.pending],
            "unsolved": list(report.unsolved),
            "failed": [{"search": what, "why": error} for what, error in report.failed]}


def parametric_text(title: str, pv, data: dict) -> str:
    """The text report of a ``ParametricVerdict`` (``data``: its :func:`parametric_data`)."""
    names = ", ".join(data["parameters"]) or "(none)"
    pos = ", ".join(data["positive"])
    lines = [paragraph(f"{title}: verdicts for every value of the parameters {names}"
                       + (f" (declared positive: {pos})" if pos else ""))]
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
    if not pv.search.complete:  # the warning says it too; here beside the cases it limits
        if pv.search.cut:
            lines.append("search cut: " + "; ".join(f"{what} ({why})" for what, why in
                                                     pv.search.cut))
        lines += [f"run failed: {what} ({error})" for what, error in pv.search.failed]
        lines += [f"  not examined: {', '.join(f'{c} = 0' for c in eqs)}"
                  for eqs in data["search"]["pending"]]
        lines += [f"  not searched: {where}" for where in pv.search.unsolved]
    return "\n".join(lines)
