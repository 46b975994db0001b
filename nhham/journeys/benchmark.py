"""Measure the integrators on a scene: ``nhham bench``.

A work-precision study (:func:`~nhham.numerics.workprecision.work_precision`): every
integration method the scene's system admits, at a ladder of tolerances or steps,
against a high-precision reference from ``[initial]`` (the loop closed by the
``[control]`` laws): error, wall time, function evaluations, constraint and energy drift.
"""

from __future__ import annotations

from typing import Mapping

from nhham.journeys.answer import Answer, as_scene, capture_warnings, quiet_steps
from nhham.journeys.simulation import closed_loop, initial_state

__all__ = ["bench"]


def bench(scene, *, t_end: float | None = None, quick: bool = False,
          reference_digits: int = 30, control: Mapping | None = None, steps=None) -> Answer:
    """The work-precision study of a scene (``nhham bench``).

    Parameters
    ----------
    scene : Scene or str
        With an ``[initial]`` table.
    t_end : float, optional
        The runs' end (default: the scene's ``[simulate]`` table, else 10).
    quick : bool
        Fewer methods and settings (a first look).
    reference_digits : int
        Digits of the reference solution.
    control : mapping of str to str, optional
        Laws replacing the scene's ``[control]`` ones.
    steps : Steps, optional

    Returns
    -------
    Answer
        ``data``: the ``result`` of ``nhham bench --json`` (``rows`` of method, setting,
        error, time...; ``time_to_solution``); ``payload["result"]``: the
        :class:`~nhham.numerics.workprecision.WorkPrecisionResult` (absent when no
        reference could be computed: then ``failure`` says why).

    Examples
    --------
    >>> from nhham import loads_scene
    >>> from nhham.journeys import bench
    >>> scene = loads_scene(\'\'\'
    ... coordinates = ["x"]
    ... lagrangian = "x_dot**2/2 - x**2/2"
    ... constraints = []
    ... [initial]
    ... x = 1.0
    ... x_dot = 0.0
    ... \'\'\')
    >>> answer = bench(scene, t_end=1.0, quick=True)
    >>> answer.succeeded and len(answer.data["rows"]) > 0
    True
    """
    from nhham.numerics.status import NumericalFailure
    from nhham.numerics.workprecision import work_precision
    from nhham.render.results import bench_data, bench_failure, bench_failure_data

    scene = as_scene(scene, check_initial=False)
    steps = quiet_steps(steps)
    y0, solved = initial_state(scene, False, steps)
    t_end = float(t_end if t_end is not None else (scene.simulate.t_end or 10.0))
    title = scene.name or str(scene.source)
    study = "work-precision study" + (" (--quick)" if quick else "")
    try:
        with capture_warnings() as caught:
            with steps.step(study):
                result = work_precision(closed_loop(scene, control), y0, (0.0, t_end),
                                        quick=quick, progress=steps.progress,
                                        reference_digits=reference_digits)
    except NumericalFailure as exc:  # no reference: nothing to measure against
        return Answer("bench", bench_failure_data((0.0, t_end), reference_digits),
                      lambda: f"work-precision: {title}, t in [0, {t_end:g}]: nothing "
                              f"measured (no reference solution)",
                      failure=bench_failure(exc, str(scene.source)), system=scene.system)
    data = bench_data(result)
    data["plot"] = None
    return Answer("bench", data, result.describe, warnings=tuple(solved + list(caught)),
                  payload={"result": result}, system=scene.system)
