"""What a study ships to its workers, and what a worker does with it.

A :class:`Study` is plain data: the scene's text, the hash of the code generated from it,
the :class:`~nhham.study.points.Design` and the options. No function, compiled library or
sympy object crosses a process boundary (lambdified functions do not pickle, and a
worker on another machine has its own compile cache). A worker builds the scene's numeric
model once (:func:`context`: the scene parsed, its generated sources found in the compile
cache or generated, its library found or compiled) and checks that its code is the one
the study was made with; it keeps the model for every later chunk of the same study.
:func:`evaluate` computes one region of the design.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field

from nhham.errors import BudgetExceeded, ComputationError
from nhham.study.kinds import kind_of
from nhham.study.lines import extended, trimmed
from nhham.study.points import Design

__all__ = ["Study", "Context", "context", "evaluate", "keep_context", "study_model",
           "study_system", "study_values", "warm"]


@dataclass(frozen=True)
class Study:
    """A study as its workers receive it.

    Attributes
    ----------
    what : {"linearize", "simulate", "classify"}
    scene_text : str
        The scene file's text (parsed by each worker, never evaluated as Python).
    scene_source : str
        Where it came from (for messages).
    code_hash : str
        SHA-256 of the model's generated Python and C texts
        (:func:`~nhham.numerics.codegen.emit.sources_digest`); empty for ``classify``.
    design : Design
    options : dict
        What the evaluation of ``what`` needs (plain data; see the modules
        :mod:`~nhham.study.stability`, :mod:`~nhham.study.ensemble`,
        :mod:`~nhham.study.classes`). ``options["values"]``, when present: the
        parameter values every point has (``--set``), replacing the scene's.
    """

    what: str
    scene_text: str
    scene_source: str
    code_hash: str
    design: Design
    options: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Context:
    """A worker's scene and model of one study (built once per worker and code hash)."""

    scene: object
    model: object


_CONTEXTS: OrderedDict = OrderedDict()
_KEPT = 4
_LOCK = threading.Lock()


def warm(scene_text: str, source: str, what: str, values: tuple = ()) -> str:
    """Build this worker's context for a scene before its study arrives (the scene
    parsed with the parameter ``values``, pairs; its model generated or found in the
    compile cache); returns the code hash."""
    from nhham.system.scene import loads_scene

    scene = loads_scene(scene_text, source, check_initial=False, values=dict(values))
    model, code_hash = study_model(scene, what)
    with _LOCK:
        _CONTEXTS[(code_hash, scene_text, tuple(values))] = Context(scene, model)
        while len(_CONTEXTS) > _KEPT:
            _CONTEXTS.popitem(last=False)
    return code_hash


def study_model(scene, what) -> tuple:
    """(numeric model or None, the hash of its generated code) of a study of ``what``."""
    if kind_of(what).system is None:
        return None, ""
    from nhham.numerics.codegen import numeric_model
    from nhham.numerics.codegen.emit import sources_digest

    model = numeric_model(study_system(scene, what))
    return model, sources_digest({"python": model.python_source, "c": model.c_source})


def context(study: Study) -> Context:
    """The scene and numeric model of ``study`` in this process, built on first use.

    Raises
    ------
    ComputationError
        When the model built here has other code than the study's (another version of
        nhham on this worker).
    """
    key = _key(study)
    with _LOCK:
        ctx = _CONTEXTS.get(key)
        if ctx is not None:
            _CONTEXTS.move_to_end(key)
            return ctx
    from nhham.system.scene import loads_scene

    scene = loads_scene(study.scene_text, study.scene_source, check_initial=False,
                        values=dict(study_values(study)))
    model, built = study_model(scene, study.what)
    if built != study.code_hash:
        raise ComputationError(
            f"this worker generates other code for {study.scene_source} than the process "
            f"that made the study (another version of nhham?): {built[:12]} against "
            f"{study.code_hash[:12]}")
    ctx = Context(scene, model)
    with _LOCK:
        _CONTEXTS[key] = ctx
        while len(_CONTEXTS) > _KEPT:
            _CONTEXTS.popitem(last=False)
    return ctx


def keep_context(study: Study, scene, model) -> None:
    """Hold the scene and model the study was prepared with in this process, so that
    chunks run here (synchronously, or by a cluster of threads) do not build them again."""
    with _LOCK:
        _CONTEXTS[_key(study)] = Context(scene, model)
        while len(_CONTEXTS) > _KEPT:
            _CONTEXTS.popitem(last=False)


def study_values(study: Study) -> tuple:
    """The parameter values every point of ``study`` has (``--set``), as pairs."""
    return tuple((str(k), float(v)) for k, v in study.options.get("values", {}).items())


def _key(study: Study) -> tuple:
    """A worker's context is the same for the same code, scene text and set values."""
    return (study.code_hash, study.scene_text, study_values(study))


def study_system(scene, what: str):
    """The system a study of ``what`` evaluates: the scene's ``[control]`` laws close
    the loop of a simulation and of a linearisation (as ``nhham simulate`` and ``nhham
    linearize`` do; the inputs without a law stay at their steady values)."""
    system = kind_of(what).system
    if system == "steady":
        return scene.steady_system()
    if system == "closed loop" and scene.control:
        return scene.system.closed_loop(dict(scene.control))
    return scene.system


def evaluate(study: Study, region: tuple, until: float | None = None) -> dict:
    """The study's variables on one region of its design (one slice per dimension).

    ``until``: a ``time.time()`` after which the chunk is not finished (a simulation
    stops inside its runs, whatever their length):
    :class:`~nhham.errors.BudgetExceeded` is raised and nothing of the chunk is kept.
    A wall-clock time, the same in every process of one machine (``time.perf_counter``
    is not).

    Returns
    -------
    dict of str to ndarray
        By variable name (see ``variables`` of the module of ``study.what``), each of the
        region's shape followed by the variable's own dimensions.
    """
    if until is not None and time.time() > until:
        raise BudgetExceeded("the study's --budget ran out")
    evaluate_kind = kind_of(study.what).load().evaluate
    along = study.options.get("along")
    if along is None:
        return evaluate_kind(study, context(study), region, until=until)
    # a piece of a line longer than a chunk: with the point before it (lines.py), along
    # the grid's second axis too
    axis = study.design.dims.index(along)
    across = study.options.get("across")
    if across is None:
        grown, added = extended(region, axis)
        return trimmed(evaluate_kind(study, context(study), grown, until=until), axis, added)
    b = study.design.dims.index(across)
    grown, (added, added_b) = extended(region, axis, b)
    return trimmed(evaluate_kind(study, context(study), grown, until=until), axis, added, b,
                   added_b)
