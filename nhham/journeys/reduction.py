"""Reduce a Chaplygin scene to its shape space and look for Chaplygin's multiplier:
``nhham reduce`` and ``nhham hamiltonize``.

:func:`reduce` gives the reduced data of an abelian Chaplygin system
(:mod:`nhham.lagrangian.chaplygin`) with the check that the reduced field lifted back is
P(xi_L); :func:`hamiltonize` decides whether a conformal factor makes the reduced system
Hamiltonian (:mod:`nhham.hamiltonian.hamiltonization`).
"""

from __future__ import annotations

import functools

from nhham.journeys.answer import Answer, as_scene, quiet_steps

__all__ = ["reduce", "hamiltonize"]


def reduce(scene, *, symmetry=None, steps=None) -> Answer:
    """The Chaplygin reduction of a scene (``nhham reduce``).

    Parameters
    ----------
    scene : Scene, System or str
    symmetry : sequence of str, optional
        The symmetry coordinates (default: found among the cyclic ones).
    steps : Steps, optional

    Returns
    -------
    Answer
        ``data``: ``shape_coordinates``, ``symmetry_coordinates``, ``connection`` (A with
        s' = -A r'), ``reduced_lagrangian``, ``momenta`` (J), ``curvature`` (B^a),
        ``gyroscopic`` (J B r'), ``accelerations``, ``reconstruction``, ``check``;
        ``failure`` when the lifted field is not P(xi_L) (a defect to report).

    Examples
    --------
    >>> from nhham import models
    >>> from nhham.journeys.reduction import reduce
    >>> answer = reduce(models.nonholonomic_particle())
    >>> answer.data["symmetry_coordinates"], answer.data["check"]["agrees"]
    (['z'], True)
    """
    from nhham.lagrangian.chaplygin import chaplygin_reduction
    from nhham.render.reduction import reduce_latex, reduce_text

    scene = as_scene(scene)
    steps = quiet_steps(steps)
    with steps.step("Chaplygin reduction, and its check against P(xi_L)"):
        red = chaplygin_reduction(scene.system, symmetry)
    data = red.to_dict()
    failure = None if red.check.value else (
        "the reduced field lifted back differs from P(xi_L); please report this scene as a bug")
    title = scene.name or str(scene.source)
    return Answer("reduce", data, lambda: reduce_text(title, data),
                  latex=functools.partial(reduce_latex, title, data), failure=failure,
                  payload={"reduction": red}, system=scene.system)


def hamiltonize(scene, *, symmetry=None, steps=None) -> Answer:
    """Whether a Chaplygin scene is Hamiltonian after a change of time
    (``nhham hamiltonize``).

    Parameters
    ----------
    scene : Scene, System or str
    symmetry : sequence of str, optional
    steps : Steps, optional

    Returns
    -------
    Answer
        ``data``: ``hamiltonizable``, ``conformal_factor`` (f with d(f Omega_nh) = 0),
        ``invariant_measure_density`` (f^(k-1)), ``divergence``, ``theta``,
        ``jacobiator_before``, ``jacobiator_after``, ``obstruction``,
        ``shape_coordinates``, ``symmetry_coordinates``, ``variables``, ``hamiltonian``,
        and the reduction's ``reduction_check``.

    Examples
    --------
    >>> from nhham import models
    >>> from nhham.journeys.reduction import hamiltonize
    >>> answer = hamiltonize(models.nonholonomic_particle())
    >>> answer.data["hamiltonizable"], answer.data["conformal_factor"]
    (True, '1/sqrt(y**2 + 1)')
    """
    from nhham.hamiltonian.hamiltonization import hamiltonize as find
    from nhham.lagrangian.chaplygin import chaplygin_reduction
    from nhham.render.reduction import hamiltonize_latex, hamiltonize_text

    scene = as_scene(scene)
    steps = quiet_steps(steps)
    with steps.step("Chaplygin reduction, and its check against P(xi_L)"):
        red = chaplygin_reduction(scene.system, symmetry)
    with steps.step("theta ^ Omega_nh = -d Omega_nh, the factor and the Jacobiators"):
        found = find(red, part=steps.part)
    data = found.to_dict()
    data["reduction_check"] = red.to_dict()["check"]
    warnings = () if found.divergence in (None, 0) else (
        f"div(f^(k-1) X) = {found.divergence} is not zero: the measure is not invariant "
        f"(please report this scene)",)
    title = scene.name or str(scene.source)
    return Answer("hamiltonize", data, lambda: hamiltonize_text(title, data),
                  latex=functools.partial(hamiltonize_latex, title, data), warnings=warnings, payload={"hamiltonization": found, "reduction": red},
                  system=scene.system)
