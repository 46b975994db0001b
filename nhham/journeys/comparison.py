"""Cross-check a scene's two sides: ``nhham compare``.

The Lagrangian and Hamiltonian sides compared through the Legendre map
(Leg_*(P(ξ_L)) = X ∘ Leg, Leg*ω_Q = ω_L, the brackets; decided exactly or at exact
points), and the Dirac-bracket flow of H against the projected field on M_f (they agree
for holonomic constraints, not for truly nonholonomic ones). At the scene's values.
"""

from __future__ import annotations

import functools

from nhham.errors import BudgetExceeded, NhhamError
from nhham.journeys.answer import Answer, as_scene, quiet_steps
from nhham.render.text import one_line
from nhham.lagrangian.engine import Policy

__all__ = ["compare"]


def compare(scene, *, policy: Policy | None = None, steps=None) -> Answer:
    """The Lagrangian/Hamiltonian cross-check of a scene (``nhham compare``).

    Parameters
    ----------
    scene : Scene, System or str
    policy : Policy, optional
    steps : Steps, optional

    Returns
    -------
    Answer
        ``data``: the ``result`` of ``nhham compare --json`` (``agree``, ``checks``,
        ``dirac``...); ``failure`` set when the sides disagree (a defect to report).

    Examples
    --------
    >>> from nhham import models
    >>> from nhham.journeys import compare
    >>> answer = compare(models.rolling_disk())
    >>> answer.data["agree"], answer.failure
    (True, None)
    """
    from nhham.hamiltonian.crosscheck import cross_check
    from nhham.hamiltonian.side import hamiltonian_side
    from nhham.journeys.verdict import at_values, with_case
    from nhham.render.results import compare_data, compare_latex, compare_text

    scene = as_scene(scene)
    steps = quiet_steps(steps)
    policy = Policy() if policy is None else policy
    if not scene.system.regular_lagrangian:
        return _singular(scene, policy, steps)
    at = at_values(scene, policy, steps)
    system = scene.system if at is None else at.system
    # One T*Q side for both checks: its numeric layer is built once.
    side = hamiltonian_side(system, closed_form=True, policy=Policy(
        precision=policy.precision, samples=policy.samples))
    with steps.step("cross-check through the Legendre map"):
        report = cross_check(system, side=side, policy=policy)
    dirac = None
    warnings = []
    with steps.step("Dirac-bracket flow of H against the projected field on M_f"):
        try:
            from nhham.hamiltonian.dirac import dirac_vs_projected

            dirac = dirac_vs_projected(system, side=side, policy=policy)
        except BudgetExceeded:  # the budget ran out: exit 3, not a warning
            raise
        except NhhamError as exc:
            warnings.append(f"Dirac comparison not available: {one_line(exc)}")
    data = compare_data(report, dirac)
    title = scene.name or str(scene.source)
    failure = None if data["agree"] else (
        "the Lagrangian and Hamiltonian sides disagree (see the checks); please report this "
        "scene as a bug")
    answer = Answer("compare", data, functools.partial(compare_text, title, report, dirac),
                    latex=functools.partial(compare_latex, title, data),
                    warnings=tuple(warnings), failure=failure,
                    payload={"report": report, "dirac": dirac}, system=scene.system)
    return with_case(answer, at)


def _singular(scene, policy, steps) -> Answer:
    """compare of a singular Lagrangian: the chain on TQ (q' = v built in) against the
    Dirac-Bergmann chain through Leg (:mod:`nhham.hamiltonian.equivalence`)."""
    import time

    from nhham.errors import InputError
    from nhham.hamiltonian.dirac_bergmann import dirac_bergmann
    from nhham.render.singular import singular_compare_data, singular_compare_text

    start = time.perf_counter()
    with steps.step("Dirac-Bergmann chain at the parameter values"):
        db = dirac_bergmann(scene.system, policy=policy)
    if not db.consistent:
        raise InputError(f"{scene.source}: the chain is inconsistent ({db.run.inconsistency});"
                         f" there are no final manifolds to compare")
    with steps.step("the chain on TQ and the comparison through Leg at points of M_f^L"):
        db.equivalence
    data = singular_compare_data(db, time.perf_counter() - start)
    data["parameter_case"] = None
    side = data["lagrangian_side"]
    failure = None
    if not data["agree"]:
        failure = (f"not compared: {side['why_not']}" if side["why_not"] else
                   "the Lagrangian and Hamiltonian chains disagree (see the checks); please "
                   "report this scene as a bug")
    title = scene.name or str(scene.source)
    return Answer("compare", data, functools.partial(singular_compare_text, title, data),
                  warnings=tuple(db.warnings), failure=failure, system=scene.system)
