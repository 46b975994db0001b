"""Run the published problems: nhham's value, its error and its time beside the source's.

:func:`run` computes every quantity of the problems asked for (all by default) and
returns a :class:`ProblemsReport`: one :class:`ProblemRow` per quantity and, where the
IFToMM bicycle ran, its maneuvers (:mod:`nhham.problems.iftomm`).
"""

from __future__ import annotations

import contextlib
from importlib import resources
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Callable, Sequence

import numpy as np

from nhham.problems.catalog import Problem, Quantity, problem, problems, scene_path
from nhham.problems.measures import MEASURES, closed_form, spectrum_error

__all__ = ["Context", "ProblemRow", "ProblemsReport", "run", "ROUNDING"]

#: A row is within the source's precision when its error is at most the printed
#: precision plus ROUNDING times the value's size (16 eps: a few roundings of double
#: precision, the floor of a 15-digit value computed either way).
ROUNDING = 16 * float(np.finfo(float).eps)


class Context:
    """A problem's scene, loaded once, and its compiled model (other parameter values
    by ``with_parameters``, no second build); ``loaded`` shares both between the problems
    of one run that name the same scene."""

    def __init__(self, prob: Problem, iftomm_rtol: float = 1e-12, loaded: dict | None = None):
        self.problem = prob
        self.iftomm_rtol = iftomm_rtol
        self._loaded = (loaded if loaded is not None else {}).setdefault(
            prob.scene, {"scenes": {}})
        self._scenes = self._loaded["scenes"]
        self.cache: dict = {}   # a measure's work shared by its quantities

    def scene(self, values=None):
        from nhham.system.scene import load_scene

        key = tuple(sorted((values or {}).items()))
        if key not in self._scenes:
            with resources.as_file(scene_path(self.problem)) as path:
                self._scenes[key] = load_scene(str(path), values=dict(values or {}))
        return self._scenes[key]

    @property
    def _model(self):
        from nhham.numerics.codegen import numeric_model

        if "model" not in self._loaded:
            self._loaded["model"] = numeric_model(self.scene().system)
        return self._loaded["model"]

    def model(self, values=None):
        return self._model.with_parameters(**values) if values else self._model

    @cached_property
    def _initial(self) -> dict:
        from nhham.journeys.simulation import initial_state

        return initial_state(self.scene())[0]

    def initial(self) -> dict:
        """The scene's [initial] state completed (by name)."""
        return self._initial

    @cached_property
    def bicycle(self):
        """The IFToMM benchmark on this scene (:class:`nhham.problems.iftomm.Benchmark`)."""
        from nhham.problems.iftomm import Benchmark

        return Benchmark(self.scene(), self.model())

    def maneuver(self, name):
        """The IFToMM maneuver ``name`` at ``iftomm_rtol``, run once."""
        return self.bicycle.run(name, self.iftomm_rtol)


@dataclass(frozen=True)
class ProblemRow:
    """One quantity: the source's value, nhham's, the error and the time.

    ``relative_error`` is |value - published| / |published| (for a spectrum: the largest
    distance between matched eigenvalues over the largest |published|; for a published
    0: the absolute error); ``within``: the absolute error is at most ``precision`` plus
    :data:`ROUNDING` times the size.
    """

    problem: str
    quantity: str
    source: str
    published: Any
    value: Any
    relative_error: float
    absolute_error: float
    precision: float
    within: bool
    time_s: float
    method: str
    note: str = ""

    def to_dict(self) -> dict:
        return {"problem": self.problem, "quantity": self.quantity, "source": self.source,
                "published": self.published, "value": self.value,
                "relative_error": _json(self.relative_error), "precision": self.precision,
                "within": self.within, "time_s": self.time_s, "method": self.method,
                "note": self.note}


@dataclass(frozen=True)
class ProblemsReport:
    """Rows of every quantity run, and the IFToMM maneuvers (empty when not run)."""

    rows: tuple
    maneuvers: tuple = field(default_factory=tuple)
    iftomm_coarsest: dict | None = None
    files: tuple = ()

    @property
    def all_within(self) -> bool:
        return all(r.within for r in self.rows)

    def to_dict(self) -> dict:
        from nhham.problems.iftomm import EXUDYN

        out = {"rows": [r.to_dict() for r in self.rows], "all_within": self.all_within,
               "files": list(self.files)}
        if self.maneuvers:
            out["iftomm"] = {
                "maneuvers": [{"name": m.name, "speed": m.speed, "roll_rate": m.roll_rate,
                               "energy_error_percent": m.energy_error_percent,
                               "integration_s": m.integration_s, "method": m.method}
                              for m in self.maneuvers],
                "coarsest": self.iftomm_coarsest,
                "exudyn": [{"energy_error_percent": e, "cpu_s": s, "step": h}
                           for e, s, h in EXUDYN]}
        return out

    def table(self) -> str:
        head = ("problem", "quantity", "published", "nhham", "rel. error", "within",
                "time s", "method")
        lines = [" | ".join(head), " | ".join("---" for _ in head)]
        for r in self.rows:
            lines.append(" | ".join([r.problem, r.quantity, _short(r.published), _short(r.value),
                                     f"{r.relative_error:.1e}", "yes" if r.within else "NO",
                                     f"{r.time_s:.3f}", r.method]))
        return "\n".join(lines)

    def render(self) -> str:
        from nhham.problems.iftomm import EXUDYN, LIBRARY_BOUND

        out = [f"published problems: {len(self.rows)} quantities, "
               + ("all within the sources' precision" if self.all_within else
                  f"{sum(not r.within for r in self.rows)} outside the sources' precision"),
               "", self.table()]
        if self.maneuvers:
            out += ["", "IFToMM uncontrolled bicycle (energy error 100 (max E - min E)/E_0, "
                        f"the library's bound {LIBRARY_BOUND:g} %):"]
            out += [f"  {m.name} (v0 = {m.speed:g}, roll rate {m.roll_rate:g}): "
                    f"{m.energy_error_percent:.2e} % in {m.integration_s:.4f} s of integration "
                    f"({m.method})" for m in self.maneuvers]
            if self.iftomm_coarsest:
                c = self.iftomm_coarsest
                out.append(f"  coarsest tolerance meeting {LIBRARY_BOUND:g} % on every maneuver: "
                           f"rtol {c['rtol']:g} (worst {c['energy_error_percent']:.2e} %, "
                           f"{c['integration_s']:.4f} s)")
            out += [f"  EXUDYN (published): {e:g} % in {s:g} s CPU (h = {h:g}, implicit "
                    f"trapezoidal rule)" for e, s, h in EXUDYN]
        for f in self.files:
            out.append(f"wrote {f}")
        return "\n".join(out)


def _json(x):
    return None if x is None or not np.isfinite(x) else float(x)


def _short(x) -> str:
    if isinstance(x, list):
        return "[" + ", ".join(_short(complex(*z)) if isinstance(z, list) else _short(z)
                               for z in x) + "]"
    if isinstance(x, complex):
        return f"{x.real:.6g}{x.imag:+.6g}i" if x.imag else f"{x.real:.6g}"
    if isinstance(x, float):
        return f"{x:.12g}"
    return str(x)


def _row(prob: Problem, q: Quantity, context: Context) -> ProblemRow:
    measured = MEASURES[q.measure](context, q.args)
    published = q.published
    note = ""
    if published == "second route":   # no value read in the source: a second integrator's
        published = measured.extra["second_route"]
        note = "published: the second route's value (the source's not read)"
    elif isinstance(published, str):   # a closed form at the scene's values
        published = closed_form(context.scene(), published, t=q.args.get("t"),
                                initial=(measured.extra or {}).get("initial")
                                or context.initial())
        note = f"closed form {q.published}"
    note = "; ".join(filter(None, [note, (measured.extra or {}).get("note", "")]))
    if isinstance(published, list):
        err = spectrum_error(measured.value, published)
        size = max(abs(complex(*z)) for z in published)
    else:
        err = abs(float(measured.value) - float(published))
        size = abs(float(published))
    rel = err / size if size else err
    # within the printed digits, or (for values printed to 15 digits) at the rounding of
    # double precision, which neither the source's computation nor nhham's goes below
    floor = (measured.extra or {}).get("floor", 0.0)   # a root's attainable accuracy
    within = err <= max(q.precision + ROUNDING * size, floor)
    if floor and err > q.precision + ROUNDING * size:
        note = (f"within the accuracy double precision gives this root ({floor:.1e}: the "
                f"spectrum's rounding over the slope of its crossing real part)")
    return ProblemRow(prob.name, q.name, f"{prob.citation}{', ' + q.where if q.where else ''}",
                      published, measured.value, float(rel), float(err), q.precision,
                      bool(within), measured.time_s, measured.method, note)


def run(names: Sequence[str] | None = None, *, iftomm_rtol: float = 1e-12,
        out_dir=None, coarsest: bool = False,
        step: Callable[[str], Any] | None = None) -> ProblemsReport:
    """Compute the published quantities of the problems ``names`` (all by default).

    Parameters
    ----------
    names : sequence of str, optional
        Problem names (``nhham.problems.problems()``); KeyError for an unknown one.
    iftomm_rtol : float
        The IFToMM bicycle's DOP853 tolerance.
    out_dir : path, optional
        Where to write the IFToMM results files (``M1.txt`` ... and
        ``bicycleResultsIFToMM.txt``).
    coarsest : bool
        Also find the coarsest tolerance meeting the library's 1e-3 % on every maneuver
        (up to 15 more runs of the bicycle).
    step : callable, optional
        ``step(text)`` a context manager around each problem's work (the command's
        progress lines, :class:`nhham.render.text.Steps`).

    Returns
    -------
    ProblemsReport

    Examples
    --------
    >>> from nhham.problems import run
    >>> report = run(["knife_edge_incline"])
    >>> [row.within for row in report.rows]
    [True, True]
    """
    chosen = [problem(n) for n in names] if names else list(problems())
    rows, maneuvers, files, best = [], [], [], None
    step = step or (lambda text: contextlib.nullcontext())
    loaded: dict = {}
    for prob in chosen:
        with step(f"problem {prob.name}"):
            context = Context(prob, iftomm_rtol, loaded)
            rows += [_row(prob, q, context) for q in prob.quantities]
            if any(q.measure == "iftomm" for q in prob.quantities):
                maneuvers, best, written = _iftomm(context, out_dir, coarsest)
                files += written
    return ProblemsReport(tuple(rows), tuple(maneuvers), best, tuple(files))


def _iftomm(context, out_dir, coarsest) -> tuple:
    from pathlib import Path

    from nhham.problems.iftomm import MANEUVERS, write_combined, write_results

    runs = [context.maneuver(name) for name in MANEUVERS]
    files = []
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        files = [str(write_results(r, out / f"{r.name}.txt")) for r in runs]
        files.append(str(write_combined(runs, out / "bicycleResultsIFToMM.txt")))
    return runs, (context.bicycle.coarsest() if coarsest else None), files
