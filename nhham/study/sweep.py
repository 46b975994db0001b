"""Parameter studies: :func:`sweep` over grids, samples and perturbed initial states.

One call prepares a study in this process (the scene loaded, its numeric model built
once, the decisions shared by every point made once: the chart of a linearisation, the
parametric classification), cuts its design into chunks, runs them where the scheduler
says (:mod:`~nhham.study.schedule`: this process, dask's threads, a local Dask cluster of
processes, a remote one) and
writes each finished chunk to the store (:mod:`~nhham.study.store`), so that an
interrupted study resumes where it stopped. The result is a :class:`SweepResult` whose
``dataset`` is the labelled xarray Dataset.
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np

from nhham.budget import time_budget
from nhham.errors import BudgetExceeded, InputError, OutputUnwritable
from nhham.study.kinds import KINDS, kind_of
from nhham.study.lines import ACROSS_VARIABLES, LINE_VARIABLES, merged
from nhham.study.points import (Axis, Design, check_seed, chunk_slices, grid, parse_over,
                                parse_perturbation, samples)
from nhham.study.schedule import check_scheduler
from nhham.study.store import (Store, attrs_text, regions_of, study_key, xarray_module,
                               zarr_module)
from nhham.study.target import check_out
from nhham.study.tasks import Study, keep_context

__all__ = ["sweep", "SweepResult"]


@dataclass(frozen=True)
class SweepResult:
    """A finished (or stopped) study.

    Attributes
    ----------
    dataset : xarray.Dataset
        The results (see the modules :mod:`~nhham.study.stability`,
        :mod:`~nhham.study.ensemble`, :mod:`~nhham.study.classes` for the variables).
    path : str or None
        Where they are (None: in memory only).
    points : int
        Points of the design.
    computed : int
        Points computed by this call (the others were found done in a resumed store).
    complete : bool
        Every point is done (False after the budget ran out or an interruption).
    wall_time_s : float
        Of this call, from the scene's load to the last chunk written.
    run_time_s : float
        Of the chunks alone: from the first task handed to the workers to the last result
        written (what more workers divide).
    scheduler : str
    workers : int
    chunks : int
        Chunks of the design (each a task).
    scene : Scene
        The scene as loaded here.
    stopped : str or None
        Why an incomplete study stopped: ``"budget"`` (its budget ran out), or the
        failure to write its store (one line); None when it is complete.
    kept : str or None
        Where its results are on disk: the output when complete, else the store to
        ``--resume`` (None: in memory).

    Examples
    --------
    The sleigh with drag (see the scene): its yaw eigenvalue -(m a U + c) / J crosses 0 at
    U* = -c / (m a) = 0.8, stable below. ``result.to_dict()`` is what ``nhham sweep
    --json`` prints.

    >>> from nhham.study.sweep import sweep
    >>> result = sweep("tests/study/scenes/sleigh_drag.toml", "linearize", ["U=0.3:1.3:6"],
    ...                workers=1)
    >>> result.points, result.computed, result.complete, result.stopped, result.path
    (6, 6, True, None, None)
    >>> result.dataset["stable"].values.tolist()       # U = 0.3, 0.5, ..., 1.3
    [True, True, True, False, False, False]
    >>> round(float(result.dataset["boundary"][0]), 6)
    0.8
    """

    dataset: Any = field(repr=False)
    path: str | None
    points: int
    computed: int
    complete: bool
    wall_time_s: float
    run_time_s: float
    scheduler: str
    workers: int
    chunks: int
    scene: Any = field(default=None, repr=False)
    stopped: str | None = None
    kept: str | None = None

    def to_dict(self) -> dict:
        """JSON-ready summary (the command's ``result``)."""
        ds = self.dataset
        return {"path": self.path, "points": self.points, "computed": self.computed,
                "complete": self.complete, "wall_time_s": self.wall_time_s,
                "run_time_s": self.run_time_s,
                "seconds_per_point": (self.run_time_s / self.computed
                                      if self.computed else None),
                "scheduler": self.scheduler, "workers": self.workers, "chunks": self.chunks,
                "dims": {d: int(ds.sizes[d]) for d in ds["done"].dims},
                "variables": sorted(ds.data_vars)}


def sweep(scene, what: str, over=(), *, samples_count: int | None = None,
          sampler: str = "lhs", seed: int = 0, initial_perturbation=(), out=None,
          resume: bool = False, overwrite: bool = False, scheduler: str | None = None,
          workers: int | None = None, client=None, budget: float | None = None,
          chunk_points: int | None = None, along: str | None = None,
          run_options: dict | None = None, policy=None, progress=None,
          values=None) -> SweepResult:
    """Run a parameter study.

    Parameters
    ----------
    scene : str or os.PathLike
        The scene file (its text is what the workers receive).
    what : {"linearize", "simulate", "classify"}
        The stability of the ``[steady]`` motion (eigenvalues, verdict, boundaries along
        ``along``), a run from the ``[initial]`` state (end state, diagnostics), or the
        constraint-set verdict, at every point.
    over : sequence of str or Axis
        ``"P=START:STOP:COUNT"`` (a grid axis), ``"P=START:STOP"`` (a range to sample) or
        ``"P=A,B,C"``; P a parameter (or, for simulate, a coordinate or velocity).
    samples_count : int, optional
        Draw this many points in the ranges (``sampler``: ``"lhs"``, ``"sobol"``,
        ``"uniform"``; ``seed``) instead of the full grid.
    initial_perturbation : sequence of str or (str, float)
        ``"NAME=SIGMA"``: normal perturbations of initial values (simulate; with
        ``samples_count``).
    out : str or os.PathLike, optional
        A ``.zarr`` directory or a ``.nc`` file; written chunk by chunk (None: memory).
        Checked before any work (:func:`~nhham.study.target.check_out`).
    resume, overwrite : bool
        Continue an interrupted study at ``out`` (made by this nhham, from the same code,
        scene and options; chunks whose data are missing are computed again); replace a
        study nhham wrote there, once the new one is complete (anything else at ``out``
        is refused).
    scheduler, workers, client
        Where the chunks run (:mod:`nhham.study.schedule`; a remote scheduler's results
        are unpickled here: use only a cluster you trust, over ``tls://``).
    budget : float, optional
        Seconds for the whole study (connecting to a scheduler, the preparation, each
        chunk's runs); what finished is kept (``complete`` False, ``stopped``
        ``"budget"``). A failed write (a full disk) also keeps what finished
        (``stopped`` says why).
    chunk_points : int, optional
        Points per chunk (default: the kind's ``chunk_points``, :data:`~nhham.study.kinds.KINDS`:
        a chunk is a task and a unit of progress, resume and writing, about a second of
        work on the bicycle).
    along : str, optional
        linearize on a grid: the parameter whose stability boundaries are located on
        every line (default: the first axis).
    run_options : dict, optional
        simulate: ``t_end``, ``method``, ``rtol``, ``atol``, ``max_step``, ``projection``
        (default: the scene's ``[simulate]`` table).
    policy : nhham.Policy, optional
        classify: the settings of the decisions.
    progress : callable, optional
        ``progress(done_points, total_points, elapsed_s)`` after each chunk.
    values : mapping of str to float, optional
        Parameter values every point has (the command's ``--set``), replacing the scene's
        (a symbolic parameter gets one); a swept name cannot have one. Stored with the
        options (``values``): a resumed study must be given the same.

    Returns
    -------
    SweepResult

    Examples
    --------
    The verdict of the scene whose constraint vanishes at a = 0 (W singular there) and
    turns underdetermined at b = +-1, at three points:

    >>> from nhham.study.sweep import sweep
    >>> ds = sweep("examples/parametric_null_constraint.toml", "classify", ["b=0.5,1.0"],
    ...            workers=1).dataset
    >>> ds["status"].values.ravel().tolist()   # 0 determined, 1 underdetermined
    [0, 1]
    """
    start = time.perf_counter()
    if budget is not None and not (math.isfinite(budget) and budget > 0):
        raise InputError(f"--budget: a positive number of seconds, got {budget!r}",
                         key="--budget")
    if chunk_points is not None and not (isinstance(chunk_points, int) and chunk_points >= 1):
        raise InputError(f"--chunk: a positive number of points, got {chunk_points!r}",
                         key="--chunk")
    deadline = None if budget is None else start + float(budget)
    kind = kind_of(what)
    # every option is checked before any work: the design's size from its counts, where
    # the results go, the scheduler and the workers
    design = _design(over, samples_count, sampler, seed, initial_perturbation, what)
    fixed = _set_values(values, design)
    xarray_module()   # installed, and of the versions the results are tested with
    if out is not None:
        zarr_module()
    target = check_out(out, resume=resume, overwrite=overwrite)
    if client is None:   # (its warning, if any, is given once, by Pool.start)
        check_scheduler(scheduler, workers, warn=False)
    text, source = _scene_text(scene)
    from nhham.study.schedule import Pool

    # the workers start, and parse the scene, while this process prepares the study
    # threads share this process's model; classify's sympy holds the GIL: processes
    with Pool.start(scheduler, workers, client, deadline=deadline, local=kind.local) as pool:
        pool.warm(text, source, what, fixed)
        # the preparation (symbolic for classify) is stopped by the budget's alarm; the
        # chunks then stop at its deadline, keeping what finished
        loaded, options, code_hash, var_spec, model = _prepared(
            text, source, what, design, along, run_options, policy, budget, deadline, fixed)
        if fixed:   # what the workers load the scene with, and part of the study's key
            options = {**options, "values": dict(fixed)}
        study = Study(what, text, source, code_hash, design, options)
        keep_context(study, loaded, model)
        attrs = _attributes(study)
        along_axis = _along_axis(design, options)
        regions = chunk_slices(design.shape, chunk_points or kind.chunk_points,
                               first=along_axis)
        chunking = _chunking(regions, design)
        written = [*var_spec["point"], *var_spec["line"], *var_spec.get("across", {})]
        if target is not None and target.resuming:
            store = Store.resume(target, attrs, written)
            regions = _resumed_regions(store, design, regions, chunk_points)
        else:
            store = Store.create(target, _template(design, var_spec, attrs,
                                                   None if target is None else chunking),
                                 chunking, _fills(var_spec))
        done = store.done(regions, written)
        pending = [r for r in regions if not done[r].all()]
        already = int(done.sum())
        counter = {"points": already}
        cut = along_axis is not None and any(r[along_axis] != slice(0, design.shape[along_axis])
                                             for r in regions)
        across_axis = (design.dims.index(options["across"]) if options.get("across")
                       else None)
        cut_across = across_axis is not None and any(
            r[across_axis] != slice(0, design.shape[across_axis]) for r in regions)

        def on_result(region, data):
            if cut:   # a piece of a line: its crossings merged with the line's stored ones
                data = merged(store.lines(design.dims, region, LINE_VARIABLES), data)
            if cut_across:   # the same for the lines along the second axis
                data = merged(store.lines(design.dims, region, ACROSS_VARIABLES), data,
                              ACROSS_VARIABLES)
            store.write(design.dims, region, data)
            counter["points"] += int((~done[region]).sum())
            done[region] = True
            if progress is not None:
                progress(counter["points"], design.size, time.perf_counter() - start)

        stopped = None
        run_start = time.perf_counter()
        try:
            pool.run(study, pending, on_result, deadline)
        except BudgetExceeded:
            stopped = "budget"
        except OutputUnwritable as exc:   # what finished is kept; exit 3 saying so
            stopped = str(exc)
        # Ctrl-C: what finished is in the store; the pool is abandoned as it is left
        run_time = time.perf_counter() - run_start
    complete = counter["points"] == design.size
    try:
        dataset = store.finish(complete=complete)
    except OutputUnwritable as exc:
        stopped, complete, dataset = str(exc), False, store.finish(complete=False)
    return SweepResult(dataset, None if out is None else os.fspath(out), design.size,
                       counter["points"] - already, complete, time.perf_counter() - start,
                       run_time, pool.scheduler, pool.workers, len(regions), loaded,
                       stopped=stopped if not complete else None,
                       kept=None if target is None else os.fspath(
                           target.path if complete else target.working))


def _prepared(text, source, what, design, along, run_options, policy, budget,
              deadline, fixed=()) -> tuple:
    """(scene, options, code hash, variables, model): the study prepared within what is
    left of its budget (symbolic work is stopped by the budget's alarm)."""
    try:
        if deadline is not None and deadline - time.perf_counter() <= 0:
            raise BudgetExceeded("")
        with time_budget(None if deadline is None else deadline - time.perf_counter()):
            loaded = _load(text, source, what, fixed)
            return (loaded,) + _prepare(what, loaded, design, along, run_options, policy)
    except BudgetExceeded:
        raise BudgetExceeded(f"the study's --budget of {budget:g} s ran out before its "
                             f"first chunk (starting the workers, loading the scene, "
                             f"building the model and the study's decisions)") from None


def _design(over, count, sampler, seed, perturbation, what) -> Design:
    check_seed(seed)
    axes = [a if isinstance(a, Axis) else parse_over(a) for a in over]
    perturbations = [p if isinstance(p, tuple) else parse_perturbation(p)
                     for p in perturbation]
    if perturbations and not kind_of(what).perturbations:
        raise InputError("--initial-perturbation: only for --what "
                         + ", ".join(k.name for k in KINDS.values() if k.perturbations),
                         key="--initial-perturbation")
    if count is None:
        if perturbations:
            raise InputError("--initial-perturbation: give --samples K (the ensemble's size)",
                             key="--initial-perturbation")
        if not axes:
            raise InputError("--over: give at least one NAME=START:STOP:COUNT (or --samples "
                             "with ranges or --initial-perturbation)", key="--over")
        return grid(axes)
    if not axes and not perturbations:
        raise InputError("--samples: give ranges to sample (--over NAME=START:STOP) or "
                         "--initial-perturbation", key="--samples")
    return samples(axes, count, sampler=sampler, seed=seed, perturbations=perturbations)


def _scene_text(scene) -> tuple:
    """(text, source) of a scene file."""
    path = Path(os.fspath(scene))
    try:
        return path.read_text(encoding="utf-8"), str(path)
    except OSError as exc:
        raise InputError(f"{path}: cannot read the scene ({exc.strerror or exc})",
                         key="scene") from None


def _set_values(values, design) -> tuple:
    """The ``--set`` values as (name, float) pairs; a name also swept is refused (which
    of the two should a point have?)."""
    fixed = tuple((str(k), float(v)) for k, v in dict(values or {}).items())
    both = [name for name, _ in fixed if name in design.names]
    if both:
        raise InputError(f"--set {both[0]}: {both[0]!r} is also swept (--over "
                         f"{both[0]}=...); give it either a value (--set) or a range "
                         f"(--over), not both", key="--set")
    return fixed


def _load(text, source, what, fixed=()):
    from nhham.system.scene import loads_scene

    # [initial] is a simulate study's start (projected onto M_1 at each point): what
    # cannot be completed is refused there; the other kinds do not read it
    try:
        scene = loads_scene(text, source, check_initial=False, values=dict(fixed))
    except InputError as exc:   # a --set name that is not a parameter
        if exc.key != "values":
            raise
        raise InputError(str(exc).replace("values: ", "--set: ", 1), key="--set") from None
    if what == "simulate" and scene.initial_problem is not None:
        raise scene.initial_problem
    # the numeric studies need W invertible; a classify study of a singular L takes the
    # chain's cases (classes.prepare) and its answer at each point
    if what != "classify":
        scene.system.require_regular_lagrangian(f"nhham sweep --what {what}")
    return scene


def _prepare(what, scene, design, along, run_options, policy) -> tuple:
    """(options, code hash, variables, numeric model) of the study, decided once here."""
    from nhham.study.tasks import study_model

    kind = kind_of(what)
    if along is not None and not kind.along:
        raise InputError(f"--along: only for --what "
                         f"{', '.join(k.name for k in KINDS.values() if k.along)}",
                         key="--along")
    model, code_hash = study_model(scene, what)
    module = kind.load()
    options = module.prepare(scene, model, design, along=along, run_options=run_options,
                             policy=policy)
    return options, code_hash, module.variables(design, options), model


def _along_axis(design, options):
    """The dimension boundaries are traced along (filled first by a chunk; a line longer
    than a chunk is cut into pieces: :mod:`~nhham.study.lines`)."""
    along = options.get("along")
    return None if along is None else design.dims.index(along)


def _resumed_regions(store, design, regions, chunk_points) -> list:
    """The regions of a resumed study: those of its store's chunks (a region written is
    a chunk of the store). Another ``--chunk`` than the store's is refused."""
    sizes = store.chunk_sizes(design.dims)
    if sizes is None or sizes == tuple(_chunking(regions, design).values()):
        return regions
    if chunk_points is not None:
        raise InputError(f"--chunk: the study at {store.working} is stored in chunks of "
                         f"{' x '.join(map(str, sizes))} points, not "
                         f"{' x '.join(map(str, _chunking(regions, design).values()))}; "
                         f"resume it without --chunk (or with the --chunk it was made with)",
                         key="--chunk")
    return regions_of(design.shape, sizes)


def _fills(spec) -> dict:
    """Each variable's fill value (what a point not computed holds)."""
    fills = {name: fill for group in ("point", "line", "across") for name, (_, _, fill) in
             spec.get(group, {}).items()}
    fills["done"] = False
    return fills


def _chunking(regions, design) -> dict:
    """Zarr chunk sizes: those of the first region (the regions form a regular grid)."""
    first = regions[0]
    return {d: len(range(*s.indices(n))) for d, s, n in zip(design.dims, first, design.shape)}


def _attributes(study) -> dict:
    from nhham.settings import __version__

    attrs = {"scene": study.scene_text, "scene_source": study.scene_source,
             "what": study.what, "design": attrs_text(study.design.description),
             "options": attrs_text({k: v for k, v in study.options.items()}),
             "code_hash": study.code_hash, "nhham_version": __version__}
    attrs["study_key"] = study_key(attrs)
    attrs["created"] = datetime.now(timezone.utc).isoformat(timespec="seconds")
    return attrs


def _template(design, spec, attrs, chunking=None):
    """The study's Dataset filled with its fill values (NaN, -1, False); with
    ``chunking`` ({dim: size}, a store on disk) its variables are lazy Dask arrays of
    those chunks (nothing of the size of the study is made in memory)."""
    from nhham.study.store import xarray_module

    xr = xarray_module()
    full = np.full
    if chunking is not None:
        import dask.array as da

        def full(shape, fill, dtype, dims=()):   # noqa: F811 - lazy on disk
            return da.full(shape, fill, dtype=dtype,
                           chunks=tuple(chunking.get(d, n) for d, n in zip(dims, shape)))
    coords = {}
    if design.kind == "grid":
        coords.update({d: design.coordinates[d] for d in design.dims})
    else:
        coords["sample"] = np.arange(design.shape[0])
        coords.update({n: ("sample", design.coordinates[n]) for n in design.names})
    # names as variable-length strings (Zarr 3 has no fixed-length unicode type)
    coords.update({k: np.array(v, dtype=object) if len(v) and isinstance(v[0], str)
                   else np.asarray(v) for k, v in spec["coords"].items()})
    data = {}
    for name, (extra, dtype, fill) in spec["point"].items():
        shape = design.shape + tuple(len(spec["coords"][d]) for d in extra)
        dims = design.dims + extra
        data[name] = (dims, full(shape, fill, dtype=dtype, **_dims(chunking, dims)))
    for group, axis in (("line", _along(attrs)), ("across", _option(attrs, "across"))):
        line_dims = tuple(d for d in design.dims if d != axis)
        for name, (extra, dtype, fill) in spec.get(group, {}).items():
            shape = tuple(design.shape[design.dims.index(d)] for d in line_dims) + tuple(
                len(spec["coords"][d]) for d in extra)
            dims = line_dims + extra
            data[name] = (dims, full(shape, fill, dtype=dtype, **_dims(chunking, dims)))
    if design.perturbed:
        data["initial_perturbation"] = (("sample", "perturbed"), design.perturbations)
        coords["perturbed"] = np.array(design.perturbed, dtype=object)
    data["done"] = (design.dims, full(design.shape, False, dtype=bool,
                                      **_dims(chunking, design.dims)))
    used = {d for v in data.values() for d in v[0]}
    coords = {k: v for k, v in coords.items()
              if k in used or (isinstance(v, tuple) and v[0] in used)}
    ds = xr.Dataset(data, coords=coords, attrs=attrs)
    for name, meaning in spec.get("attrs", {}).items():   # what a variable's codes mean
        if name in ds:
            ds[name].attrs.update(meaning)
    return ds


def _dims(chunking, dims) -> dict:
    return {} if chunking is None else {"dims": dims}


def _along(attrs) -> str | None:
    return _option(attrs, "along")


def _option(attrs, name):
    import json

    return json.loads(attrs["options"]).get(name)


def progress_line(stream=sys.stderr):
    """A ``progress`` callable printing one updating line on a terminal."""
    first: list = []

    def report(done, total, elapsed):
        # the rate of the chunks since the first one finished (the preparation before it
        # is not the chunks' pace)
        first[:] = first or [done, elapsed]
        rate = (done - first[0]) / (elapsed - first[1]) if elapsed > first[1] else 0.0
        left = f", ~{(total - done) / rate:.0f} s left" if rate > 0 else ""
        stream.write(f"\r  {done}/{total} points ({100 * done / total:.0f}%), "
                     f"{elapsed:.1f} s{left}   ")
        if done >= total:
            stream.write("\n")
        stream.flush()
    return report
