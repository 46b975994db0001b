"""Classify a scene: ``nhham classify`` and ``nhham classify --parametric``.

:func:`classify` is the verdict at the scene's parameter values: the constraint algorithm
(stages, ranks, M_f, free multipliers), integrability, and the first/second class split of
the final constraints on T*Q, where the values satisfy an exceptional condition the
answer that holds there (:func:`~nhham.verdict.values.classification_at_values`).
:func:`classify_parametric` is the verdict for every value of the parameters: the generic
one and each exceptional case (:func:`~nhham.verdict.parametric.parametric_classification`).
"""

from __future__ import annotations

import dataclasses
import functools

from nhham.errors import InputError, UsageError
from nhham.journeys.answer import Answer, as_scene, quiet_steps
from nhham.lagrangian.engine import Policy

__all__ = ["classify", "classify_parametric", "parameter_case", "symbolic_names", "at_values",
           "with_case"]


def classify(scene, *, policy: Policy | None = None, steps=None) -> Answer:
    """The constraint-set verdict at the scene's parameter values (``nhham classify``).

    Parameters
    ----------
    scene : Scene, System or str
        A scene, a system or a scene file's path (redundant constraints are dropped,
        each named in a warning).
    policy : Policy, optional
        The settings of every decision (precision, samples, seed, budget).
    steps : Steps, optional
        Where the steps are recorded and shown (the command's progress).

    Returns
    -------
    Answer
        ``data``: the ``result`` of ``nhham classify --json`` (status, stages, ranks,
        integrability, first and second class with the first-class combinations,
        ``parameter_case``); ``payload["verdict"]``: the
        :class:`~nhham.verdict.results.ValuesVerdict`.

    Raises
    ------
    InputError
        The system is not valid at its parameter values (e.g. W singular there).

    Examples
    --------
    >>> from nhham import models
    >>> from nhham.journeys import classify
    >>> answer = classify(models.rolling_disk())
    >>> answer.data["status"], answer.data["regular"], answer.data["integrable"]
    ('determined', True, False)
    >>> answer.data["first_class"], answer.data["second_class"]   # {psi_1, psi_2} = 0
    (2, 0)
    """
    from nhham.lagrangian.analysis import ConstraintAnalysis
    from nhham.render.results import (classify_data, classify_latex, classify_text,
                                      classify_warnings)

    scene = as_scene(scene, drop_redundant=True)
    steps = quiet_steps(steps)
    if not scene.system.regular_lagrangian:
        return singular_classify(scene, policy, steps)
    at = values_verdict(scene, policy, steps)
    analysis, classes = at.verdict.analysis, at.verdict.classes
    assert isinstance(analysis, ConstraintAnalysis)  # a valid verdict carries its analysis
    for stage in analysis.stages:
        for d in stage.decisions:
            steps.note(f"stage {stage.index}: {d.describe()}")
    data = classify_data(analysis, classes)
    if scene.system.time is not None and classes is not None:
        from nhham.hamiltonian.instants import split_instants

        with steps.step("instants where the first/second-class split changes"):
            found = split_instants(classes)
        if found is not None:
            data["time"]["class_split"] = found.to_dict()
    data["parameter_case"], note = parameter_case(at)
    title = scene.name or str(scene.source)
    return Answer("classify", data, lambda: classify_text(title, data) + note,
                  latex=functools.partial(classify_latex, title, data),
                  warnings=tuple(classify_warnings(analysis, classes) + list(at.warnings)),
                  payload={"verdict": at}, system=scene.system)


def singular_classify(scene, policy, steps) -> Answer:
    """``classify`` of a singular Lagrangian: the Dirac-Bergmann chain at the values
    (:func:`~nhham.hamiltonian.dirac_bergmann.dirac_bergmann`)."""
    from nhham.hamiltonian.dirac_bergmann import dirac_bergmann
    from nhham.render.singular import (singular_data, singular_latex, singular_text,
                                       singular_warnings)

    with steps.step("Dirac-Bergmann chain at the parameter values (primary constraints, "
                    "generations, classes, gauge generators)"):
        db = dirac_bergmann(scene.system, policy=policy)
        data = singular_data(db)
    for stage in db.run.stages:
        for d in stage.decisions:
            steps.note(f"generation {stage.index}: {d.describe()}")
    data["parameter_case"] = None
    title = scene.name or str(scene.source)
    return Answer("classify", data, lambda: singular_text(title, data),
                  latex=functools.partial(singular_latex, title, data),
                  warnings=tuple(singular_warnings(db)), payload={"chain": db},
                  system=scene.system)


def values_verdict(scene, policy, steps):
    """The :class:`~nhham.verdict.results.ValuesVerdict` of the scene's system at its
    values, as every command answers for them.

    Raises
    ------
    InputError
        The system is invalid there.
    """
    from nhham.verdict.values import classification_at_values

    with steps.step("constraint algorithm at the parameter values (stages, ranks, decisions "
                    "at exact points, integrability, exceptional parameter sets)"):
        at = classification_at_values(scene.system, policy=policy)
    if at.verdict.status == "invalid":
        raise InputError(f"{scene.source}: at the parameter values {at.verdict.note}")
    return at


def parameter_case(at) -> tuple:
    """(JSON ``parameter_case``, text note) of a ``ValuesVerdict``: the exceptional
    conditions the values satisfy, and whether the answer there differs from the generic
    one."""
    from nhham.render.text import expr_text

    if not at.conditions:
        return None, ""
    data = {"conditions": [expr_text(c) for c in at.conditions],
            "generic": at.generic.to_dict(), "generic_differs": bool(at.differs)}
    where = ", ".join(f"{expr_text(c)} = 0" for c in at.conditions)
    note = (f"\nnote: the parameter values satisfy {where}; the answer above holds there"
            + (f" and differs from the generic one ({at.generic.describe()})"
               if at.differs else " (the generic verdict is the same)"))
    return data, note


def at_values(scene, policy, steps):
    """The verdict at the values when some parameter has one, else None."""
    return values_verdict(scene, policy, steps) if scene.system.parameter_values else None


def with_case(answer: Answer, at) -> Answer:
    """``answer`` with the parameter case of ``at`` (None: no parameter has a value)."""
    if at is None:
        return answer.with_data(parameter_case=None)
    case, note = parameter_case(at)
    # Values near an exceptional set warn whether or not they fall in one.
    answer = dataclasses.replace(answer.with_data(parameter_case=case),
                                 warnings=tuple(answer.warnings) + tuple(at.warnings))
    if not note:
        return answer
    render, latex = answer.render, answer.latex
    return dataclasses.replace(
        answer, render=lambda: render() + note,
        latex=None if latex is None else (lambda parse: latex(parse) + note))


def classify_parametric(scene, *, policy: Policy | None = None, positive=(),
                        depth: int | None = None, symbolic=None, steps=None) -> Answer:
    """The verdict for every value of the parameters (``nhham classify --parametric``).

    Parameters
    ----------
    scene : Scene, System or str
    policy : Policy, optional
    positive : sequence of str
        Parameters declared positive (masses, lengths).
    depth : int, optional
        Bound on the nesting of cases (default 3).
    symbolic : sequence of str, optional
        The parameters kept symbolic (``["all"]``: every one); the others are held at
        their values. Default: those that nhham knows can change the classification:
        those in L and the constraints, those without a value (:func:`symbolic_names`),
        and those in the forces or the dissipation where C is singular in a verdict
        found (:data:`~nhham.verdict.parametric.NEEDED`: the runs again with them
        symbolic, when the budget allows; else a warning with the estimate).
    steps : Steps, optional

    Returns
    -------
    Answer
        ``data``: the ``result`` of ``nhham classify --parametric --json`` (``generic``,
        ``cases`` with their conditions, ``scene_case``...); ``payload["verdict"]``: the
        :class:`~nhham.verdict.results.ParametricVerdict`.

    Examples
    --------
    >>> from nhham import loads_scene
    >>> from nhham.journeys import classify_parametric
    >>> scene = loads_scene('''
    ... coordinates = ["x", "y", "z"]
    ... symbolic_parameters = ["a", "b"]
    ... lagrangian = "(x_dot**2 + y_dot**2 + z_dot**2)/2"
    ... constraints = ["x_dot + a*y", "y_dot + b*x"]
    ... ''')
    >>> answer = classify_parametric(scene)
    >>> answer.data["generic"]["second_class"], len(answer.data["cases"])
    (2, 1)
    >>> answer.data["cases"][0]["conditions"], answer.data["cases"][0]["verdict"]["first_class"]
    (['a - b'], 2)
    """
    from nhham.render.parametric import parametric_data, parametric_text
    from nhham.verdict.parametric import NEEDED, parametric_classification

    scene = as_scene(scene, drop_redundant=True)
    steps = quiet_steps(steps)
    if not scene.system.regular_lagrangian:
        return _singular_parametric(scene, policy, positive, depth, symbolic, steps)
    # The runs are parts of the step (nhham.progress): named in a budget's message,
    # listed by --verbose, shown on a terminal once the search has run a second.
    with steps.step("verdicts for every parameter value (generic run, exceptional sets, "
                    "one run per case)"):
        pv = parametric_classification(
            scene.system, positive=list(positive), max_depth=3 if depth is None else depth,
            policy=policy,
            symbolic=NEEDED if symbolic is None else symbolic_names(scene.system, symbolic))
    # The report forms what the runs left lazy (integrability, classes): a step of its own,
    # so that a budget running out there is named.
    with steps.step("the verdicts' report (integrability and classes of every case)"):
        data = parametric_data(pv)
    title = scene.name or str(scene.source)
    return Answer("classify", data, functools.partial(parametric_text, title, pv, data),
                  warnings=tuple(pv.warnings), payload={"verdict": pv}, system=scene.system)


def _singular_parametric(scene, policy, positive, depth, symbolic, steps) -> Answer:
    """``classify --parametric`` of a singular Lagrangian: the chain with the parameters
    symbolic (default every one) and the cases where its answer changes."""
    from nhham.render.singular import singular_parametric_data, singular_parametric_text
    from nhham.verdict.singular import singular_parametric

    names = None if symbolic is None else symbolic_names(scene.system, symbolic)
    with steps.step("Dirac-Bergmann chains for every parameter value (generic chain, "
                    "exceptional factors, one chain per case)"):
        pv = singular_parametric(scene.system, policy=policy, symbolic=names,
                                 positive=positive, max_depth=3 if depth is None else depth)
        data = singular_parametric_data(pv)
    data["positive"] = list(positive)
    title = scene.name or str(scene.source)
    chains = [pv.generic] + [c.chain for c in pv.cases if c.chain is not None]
    warnings = [w for chain in chains for w in chain.warnings]
    return Answer("classify", data, functools.partial(singular_parametric_text, title, data),
                  warnings=tuple(dict.fromkeys(warnings)), payload={"verdict": pv},
                  system=scene.system)


def symbolic_names(system, names=None) -> list:
    """The parameters a parametric classification keeps symbolic (names).

    None: :func:`~nhham.verdict.parametric.needed_parameters` (those in L and the
    constraints, and every parameter without a value: it cannot be held), the set the
    default exploration starts from; ``["all"]``: every parameter.

    Raises
    ------
    UsageError
        A name that is not a parameter (key ``--symbolic``), with the closest one.

    Examples
    --------
    >>> from nhham import loads_scene
    >>> s = loads_scene('''
    ... coordinates = ["x", "y"]
    ... parameters = { m = 1.0, a = 2.0, k = 3.0 }
    ... lagrangian = "m*(x_dot**2 + y_dot**2)/2"
    ... constraints = ["x_dot - a*y"]
    ... [forces]
    ... y = "-k*y"
    ... ''').system
    >>> symbolic_names(s), symbolic_names(s, ["all"])
    (['m', 'a'], ['m', 'a', 'k'])
    """
    import difflib

    from nhham.verdict.parametric import needed_parameters

    params = [p.name for p in system.declared_parameters]
    if names is None:
        return [p.name for p in needed_parameters(system)]
    names = [str(n).strip() for n in names if str(n).strip()]
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
