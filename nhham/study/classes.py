"""``--what classify``: the constraint-set verdict at every point.

The verdict changes only on exceptional parameter sets (polynomial equations in the
parameters), so a study classifies once, for every value of the swept parameters
(:func:`~nhham.verdict.parametric.parametric_classification` on the system with the
other parameters at their values, :func:`prepare`), and each point is then placed in its
case by exact arithmetic (its values read as the decimals they print as, as
``classify`` reads a scene's): the generic region, or the first case whose equations hold
there. The verdict of a case is what ``nhham classify`` answers at its first point met
(:func:`nhham.journeys.classify` on the scene at that point's values; once per case and
process): a point's variables are the command's answer there, and the other points of
its case share it because the verdict is constant on a case.

Variables: ``case`` (-1 generic, else the index of ``cases`` in the attributes),
``status`` (0 determined, 1 underdetermined, 2 inconsistent, 3 invalid), ``regular`` and
``integrable`` (1 yes, 0 no, -1 undecided), ``rank_C``, ``stages``,
``free_multipliers``, ``first_class``, ``second_class`` (-1 where not decided).
"""

from __future__ import annotations

import numpy as np

from nhham.errors import InputError

__all__ = ["prepare", "variables", "evaluate", "summary", "summary_warnings", "summary_rows",
           "STATUS_CODES", "row_of", "command_row"]

#: ``status`` codes.
STATUS_CODES = {"determined": 0, "underdetermined": 1, "inconsistent": 2, "invalid": 3}

_FIELDS = ("status", "regular", "integrable", "rank_C", "stages", "free_multipliers",
           "first_class", "second_class")


def prepare(scene, model, design, *, along=None, run_options=None, policy=None) -> dict:
    """The parametric classification over the swept parameters, as plain data.

    Raises
    ------
    InputError
        A swept name that is not a parameter with a value.
    """
    import sympy as sp

    from nhham.system.expressions import to_text
    from nhham.verdict.parametric import parametric_classification
    from nhham.verdict.results import exact_value
    from nhham.verdict.substitution import rebuild

    system = scene.system
    values = {p.name: v for p, v in system.parameter_values.items()}
    for name in design.names:
        if name not in values:
            raise InputError(f"--over: {name!r} is not a parameter with a value in the scene "
                             f"(parameters: {', '.join(values) or 'none'})", key="--over")
    fixed = {sp.Symbol(k): exact_value(v) for k, v in values.items() if k not in design.names}
    if not system.regular_lagrangian:
        return _singular_cases(system, design, policy)
    reduced = rebuild(system, {p: v for p, v in fixed.items() if p in system.parameters},
                      None)
    if not hasattr(reduced, "coordinates"):   # a Verdict: invalid at the fixed values
        raise InputError(f"--what classify: {reduced.note}", key="parameters")
    verdict = parametric_classification(reduced, policy=policy)
    return {
        "generic": _row(verdict.generic),
        "cases": [{"conditions": [to_text(c) for c in case.conditions],
                   "excluding": [to_text(c) for c in case.excluding],
                   "verdict": _row(case.verdict),
                   "describe": case.describe()} for case in verdict.cases],
        "generic_describe": verdict.generic.describe(),
        "notes": list(verdict.notes),
        "names": list(design.names),
        # the settings of the command run at a point of each case (its budget aside)
        "policy": _policy_data(policy),
    }


def _singular_cases(system, design, policy) -> dict:
    """:func:`prepare` for a singular Lagrangian: the cases of ``classify --parametric``
    (the Dirac-Bergmann chain with the swept parameters symbolic), the most specific first
    so that a point takes the first whose equations hold; every point's variables are the
    chain's answer there (:func:`command_row`)."""
    from nhham.render.singular import singular_data
    from nhham.system.expressions import to_text
    from nhham.verdict.singular import singular_parametric

    found = singular_parametric(system, policy=policy, symbolic=list(design.names))
    invalid = dict.fromkeys(_FIELDS, -1) | {"status": STATUS_CODES["invalid"]}
    cases = sorted(found.cases, key=lambda c: -len(c.conditions))
    return {
        "generic": row_of(singular_data(found.generic)),
        "cases": [{"conditions": [to_text(c) for c in case.conditions], "excluding": [],
                   "verdict": invalid if case.chain is None else row_of(singular_data(case.chain)),
                   "describe": case.failure or "; ".join(case.reasons)} for case in cases],
        "generic_describe": "the Dirac-Bergmann chain with "
                            + ", ".join(design.names) + " symbolic",
        "notes": [],
        "names": list(design.names),
        "policy": _policy_data(policy),
    }


def _policy_data(policy) -> dict | None:
    import dataclasses

    if policy is None:
        return None
    return {k: v for k, v in dataclasses.asdict(policy).items() if k != "budget"}


def _row(verdict) -> dict:
    """A verdict as the integer codes of the variables."""
    def tri(x):
        return -1 if x is None else int(bool(x))

    def count(x):
        return -1 if x is None else int(x)

    return {"status": STATUS_CODES[verdict.status], "regular": tri(verdict.regular),
            "integrable": tri(verdict.integrable), "rank_C": count(verdict.rank_C),
            "stages": count(verdict.stages), "free_multipliers": count(verdict.free_multipliers),
            "first_class": count(verdict.first_class),
            "second_class": count(verdict.second_class)}


def variables(design, options) -> dict:
    """``{"point": {name: (extra dims, dtype, fill)}, "line": {}, "coords": {}}``."""
    point: dict = {"case": ((), np.int16, -2)}
    point.update({f: ((), np.int8 if f in ("status", "regular", "integrable") else np.int16,
                      -1) for f in _FIELDS})
    return {"point": point, "line": {}, "coords": {}}


def evaluate(study, ctx, region, until: float | None = None) -> dict:
    """Every variable on ``region``: each point placed in its case exactly."""
    import sympy as sp

    from nhham.system.expressions import parse_expression
    from nhham.verdict.results import exact_value

    opts = study.options
    names = opts["names"]
    table = {n: sp.Symbol(n) for n in names}
    cases = [([parse_expression(c, table) for c in case["conditions"]],
              [parse_expression(c, table) for c in case["excluding"]])
             for case in opts["cases"]]
    values = study.design.values(region)
    shape = next(iter(values.values())).shape
    out = {f: np.empty(shape, dtype=np.int16) for f in ("case",) + _FIELDS}
    for index in np.ndindex(*shape):
        values_here = {n: float(values[n][index]) for n in names}
        point = {table[n]: exact_value(v) for n, v in values_here.items()}
        which = -1
        for i, (eqs, neqs) in enumerate(cases):
            if (all(e.xreplace(point) == 0 for e in eqs)
                    and all(e.xreplace(point) != 0 for e in neqs)):
                which = i
                break
        row = _case_row(study, which, values_here)
        out["case"][index] = which
        for f in _FIELDS:
            out[f][index] = row[f]
    return out


#: The command's answer per (scene, case), in this process.
_ROWS: dict = {}


def _case_row(study, which: int, values: dict) -> dict:
    """The variables of case ``which`` (-1: the generic region): ``nhham classify`` at
    ``values`` (the first point of the case met in this process)."""
    # a case's index means something only in its study (its cases, names and policy)
    key = (study.scene_text, repr(sorted(study.options.items())), which)
    if key in _ROWS:
        return _ROWS[key]
    point = key + (tuple(sorted(values.items())),)
    if point not in _ROWS:
        # the point's values over those every point has (--set)
        given = {**dict(study.options.get("values") or {}), **values}
        row, singular = command_row(study.scene_text, study.scene_source, given,
                                    study.options.get("policy"), with_kind=True)
        # a singular L's chain answers point by point: its answer is not the case's
        _ROWS[point if singular else key] = row
    return _ROWS.get(key) or _ROWS[point]


def command_row(scene_text: str, source: str, values: dict, policy=None,
                with_kind: bool = False):
    """The study's variables of ``nhham classify`` on the scene at ``values`` (a
    parameter name -> value mapping, as ``--set`` gives them); with ``with_kind``
    (row, whether L is singular there: the Dirac-Bergmann chain answered)."""
    from nhham.journeys.verdict import classify
    from nhham.lagrangian.engine import Policy
    from nhham.system.scene import loads_scene

    try:
        scene = loads_scene(scene_text, source, check_initial=False, drop_redundant=True,
                            values=values)
        data = classify(scene, policy=Policy(**policy) if policy else None).data
    except InputError:   # the command refuses the system there
        row = dict.fromkeys(_FIELDS, -1) | {"status": STATUS_CODES["invalid"]}
        return (row, False) if with_kind else row
    return (row_of(data), "lagrangian_rank" in data) if with_kind else row_of(data)


def row_of(data) -> dict:
    """The integer codes of the variables of a ``nhham classify`` result."""
    def tri(x):
        return -1 if x is None else int(bool(x))

    def count(x):
        return -1 if x is None else int(x)

    return {"status": STATUS_CODES[data["status"]], "regular": tri(data["regular"]),
            "integrable": tri(data["integrable"]), "rank_C": count(data["rank_c"]),
            "stages": count(len(data["stages"])),
            "free_multipliers": count(data["free_multipliers"]),
            "first_class": count(data["first_class"]),
            "second_class": count(data["second_class"])}


def summary(ds) -> dict:
    """What the study found, in a few numbers (JSON-ready): points per case."""
    done = np.asarray(ds["done"].values, dtype=bool)
    case = np.asarray(ds["case"].values)[done]
    return {"done_points": int(done.sum()), "generic_points": int((case == -1).sum()),
            "case_points": {str(int(c)): int((case == c).sum())
                            for c in np.unique(case) if c >= 0}}


def summary_warnings(s: dict) -> list:
    """The warnings a summary calls for (none)."""
    return []


def summary_rows(s: dict) -> list:
    """(label, text) rows of the command's report."""
    return [("generic verdict", f"{s['generic_points']} points")] + [
        (f"case {c}", f"{n} points") for c, n in s["case_points"].items()]
