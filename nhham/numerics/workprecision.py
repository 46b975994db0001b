"""Work-precision: error against a high-precision reference versus cost.

:func:`work_precision` runs every method at a ladder of settings on one
problem and measures, for each run, the error at t_end against a reference, the
wall time, the evaluations, the constraint residual and the energy drift.

- The reference is the mpmath extrapolation of :mod:`nhham.numerics.reference`
  (``quick``: compiled DOP853 at rtol 1e-13 with projection, in float64; seconds
  instead of minutes). It must be far more accurate than the tightest setting; its own
  error estimate is recorded and a :class:`~nhham.numerics.model.NumericsWarning` is
  issued if it is not at least 100 times below the smallest error measured. If it
  cannot be computed (the field is singular at the initial state, say), nothing can
  be measured: :class:`~nhham.numerics.status.NumericalFailure` says why.
- Each setting is run until the runs together took ``min_time`` (as ``timeit``'s
  autorange does): a sub-millisecond run is repeated hundreds of times and the median
  reported, so that the timings of neighbouring settings do not zig-zag with noise.
- A method's tighter settings are skipped once one of its runs took longer than
  ``slow`` seconds (they would take longer still); the result lists them. A run is
  stopped at twice ``slow`` (``Status.TIME_LIMIT``: a failed row).
"""

from __future__ import annotations

import math
import statistics
import sys
import time
import warnings
from dataclasses import asdict, dataclass

import numpy as np

from nhham.numerics.diagnostics import singularity_at
from nhham.numerics.nullspace import KKT_SOLVE, diagonal_ratio
from nhham.numerics.integrate import simulate
from nhham.numerics.methods import DEFAULT_METHOD, lookup, names
from nhham.numerics.model import NumericModel, NumericsWarning
from nhham.numerics.status import NumericalFailure, Status

__all__ = ["WorkPrecisionRow", "WorkPrecisionResult", "work_precision", "DEFAULT_TOLERANCES"]

DEFAULT_TOLERANCES = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
_STEP_DIVISIONS = (25, 50, 100, 200, 400, 800, 1600, 3200, 6400)
_QUICK_TOLERANCES = (1e-5, 1e-8)
_QUICK_DIVISIONS = (50, 200, 800)
#: The float64 reference of ``quick``: DOP853 at this rtol (atol 1e-3 rtol), with
#: projection; its error is estimated by a run at ten times the tolerance.
QUICK_REFERENCE_RTOL = 1e-13


@dataclass(frozen=True)
class WorkPrecisionRow:
    """One setting of one method.

    Attributes
    ----------
    method : str
        Method label (``DOP853``, ``DOP853+projection``, ``rattle``...).
    setting : str
        ``"rtol=1e-08"`` or ``"h=0.01"``.
    error : float
        ||y(t_end) - y_ref(t_end)||_2 / ||y_ref(t_end)||_2 (absolute if the
        reference state is zero); inf when the run failed.
    wall_time_s : float
        Median over the runs.
    nfev : int
    constraint_residual : float
        Largest absolute constraint residual along the run.
    energy_drift : float
        max |E(t) - E(0)| along the run.
    energy_balance_residual : float
    status : int
        A :class:`~nhham.numerics.status.Status` code.
    runs : int
        How many times the setting was run for its timing.
    """

    method: str
    setting: str
    error: float
    wall_time_s: float
    nfev: int
    constraint_residual: float
    energy_drift: float
    energy_balance_residual: float
    status: int
    runs: int = 1

    @property
    def status_name(self) -> str:
        """``success``, ``singular``, ``step_failed``, ... (:class:`Status` in lower case)."""
        return Status(self.status).name.lower()


@dataclass(frozen=True)
class WorkPrecisionResult:
    """Rows of a work-precision study and the reference used.

    Attributes
    ----------
    rows : tuple of WorkPrecisionRow
    name : str
    t_span : (float, float)
    reference_digits : int
        Digits of the mpmath reference (16 for the float64 reference of ``quick``).
    reference_error_estimate : float
    reference_wall_time_s : float
    backend : str
    reference : str
        What the reference is, in words.
    skipped : tuple of (method, setting, reason)
        Settings not run (a looser one of the same method was already slow).
    forced : str
        Why the energy is not conserved ("" where it is: ``NumericModel.energy_change``):
        the system has forces, t in L or a constraint, affine constraints whose reactions
        do work, or a nonlinear (Chetaev) one; the table then shows the energy balance
        residual max |E(t) - E(0) - ∫ P dt| (P the power of the applied, dissipative and
        constraint forces, and -dL/dt) instead of the energy drift, and says why.
    kkt_solve : str
        The solve of the constrained accelerations: ``"null-space"``
        (:mod:`nhham.numerics.nullspace`).
    kkt_ratio_max : float
        The larger max W_AA / min W_AA at the initial state and the reference's end (the
        spread of the masses in the scene's units, a diagnostic).
    """

    rows: tuple
    name: str
    t_span: tuple
    reference_digits: int
    reference_error_estimate: float
    reference_wall_time_s: float
    backend: str
    reference: str = ""
    skipped: tuple = ()
    forced: str = ""
    kkt_solve: str = KKT_SOLVE
    kkt_ratio_max: float = 1.0

    def methods(self) -> tuple:
        seen = []
        for r in self.rows:
            if r.method not in seen:
                seen.append(r.method)
        return tuple(seen)

    def time_to_solution(self, target: float) -> dict:
        """Per method: the least wall time of a run with error <= target (None if none)."""
        out = {}
        for method in self.methods():
            ok = [r.wall_time_s for r in self.rows
                  if r.method == method and r.status == 0 and r.error <= target]
            out[method] = min(ok) if ok else None
        return out

    def as_dicts(self) -> list:
        return [asdict(r) for r in self.rows]

    def to_dict(self) -> dict:
        """Plain data for JSON: rows, reference, time to solution at 1e-6 and 1e-10."""
        return {
            "name": self.name, "t_span": list(self.t_span), "backend": self.backend,
            "reference": self.reference, "reference_digits": self.reference_digits,
            "reference_error_estimate": self.reference_error_estimate,
            "reference_wall_time_s": self.reference_wall_time_s,
            "rows": self.as_dicts(),
            "kkt_solve": self.kkt_solve, "kkt_ratio_max": self.kkt_ratio_max,
            "skipped": [list(s) for s in self.skipped],
            "time_to_solution": {"1e-06": self.time_to_solution(1e-6),
                                 "1e-10": self.time_to_solution(1e-10)},
        }

    def describe(self) -> str:
        """The table and the time to solution at relative errors 1e-6 and 1e-10."""
        lines = [f"work-precision: {self.name or 'system'}, t in {list(self.t_span)}, backend "
                 f"{self.backend}; reference: {self.reference} (estimated error "
                 f"{self.reference_error_estimate:.1e}, {self.reference_wall_time_s:.3g} s)",
                 "", self.table(), ""]
        if self.forced:
            lines.append(f"energy balance, not drift: the energy is not conserved here "
                         f"({self.forced}); the balance residual measures each method's error")
        if self.skipped:
            lines.append("skipped: " + "; ".join(f"{m} {s} ({why})"
                                                 for m, s, why in self.skipped))
        for target in (1e-6, 1e-10):
            tts = self.time_to_solution(target)
            best = sorted((v, k) for k, v in tts.items() if v is not None)
            text = ", ".join(f"{k} {1e3 * v:.3g} ms" for v, k in best) or "none reached it"
            lines.append(f"time to relative error {target:.0e}: {text}")
        return "\n".join(lines)

    def table(self) -> str:
        """Markdown table of all rows (wall time: the median of the runs)."""
        energy = "energy balance" if self.forced else "energy drift"
        head = ("| method | setting | error at t_end | wall time [ms] | runs | evaluations | "
                f"constraint residual | {energy} |\n|---|---|---|---|---|---|---|---|")
        lines = [head]
        for r in self.rows:
            flag = "" if r.status == 0 else f" (failed: {r.status_name})"
            e = r.energy_balance_residual if self.forced else r.energy_drift
            lines.append(f"| {r.method} | {r.setting}{flag} | {r.error:.2e} | "
                         f"{1e3 * r.wall_time_s:.3g} | {r.runs} | {r.nfev} | "
                         f"{r.constraint_residual:.1e} | {e:.1e} |")
        return "\n".join(lines)


def work_precision(system_or_model, y0, t_span, *, methods=None, tolerances=DEFAULT_TOLERANCES,
                   steps=None, projection_variants: bool = True, reference_digits: int = 30,
                   repeats: int = 1, backend: str = "auto", quick: bool = False,
                   progress: bool = False, loop: str = "auto", min_time: float | None = None,
                   slow: float | None = None) -> WorkPrecisionResult:
    """Run every method at every setting and measure error and cost.

    Parameters
    ----------
    system_or_model : nhham.System or NumericModel
    y0 : mapping or array_like
        A state on M_1.
    t_span : (float, float)
    methods : sequence of str, optional
        Default: every adaptive method, and the fixed-step ones that take the system
        (RATTLE and its composition when L is quadratic and there are no forces, RK4
        unless the forces depend on t); with ``quick`` DOP853, Radau, LSODA and those.
    tolerances : sequence of float
        rtol ladder of the adaptive methods (atol = rtol * 1e-3).
    steps : sequence of float, optional
        Steps of the fixed-step methods (default (t1 - t0)/N for N in
        25..6400).
    projection_variants : bool
        Also run every adaptive method and rk4 with projection onto M_1.
    reference_digits : int
        Digits of the mpmath reference.
    repeats : int
        Least number of runs per setting; the median wall time is reported.
    backend : str
    quick : bool
        A small study in seconds: DOP853, Radau, LSODA and the fixed-step methods at
        two or three settings each, the float64 reference (see the module docstring),
        ``min_time`` 0.02 s and ``slow`` 0.5 s.
    progress : bool
        Print each setting on stderr as it runs, with its time.
    loop : {"auto", "compiled", "scipy"}
        Passed to :func:`~nhham.numerics.integrate.simulate` for the scipy methods
        (RK23, RK45 and DOP853 run as one compiled loop by default when the
        model is compiled; ``"scipy"`` measures scipy's Python loop instead).
    min_time : float, optional
        Run each setting until its runs took this long together (default 0.2 s).
    slow : float, optional
        Skip a method's tighter settings after a run longer than this (default 20 s).

    Raises
    ------
    NumericalFailure
        When the reference cannot be computed (its message says why and where).

    Examples
    --------
    RK4 is of order 4: halving its step divides the error by 2**4 = 16.

    >>> from nhham import System, work_precision
    >>> spring = System(["x"], "x_dot**2/2 - x**2/2")
    >>> study = work_precision(spring, {"x": 1.0, "x_dot": 0.0}, (0.0, 1.0), methods=["rk4"],
    ...                        steps=(0.1, 0.05), projection_variants=False,
    ...                        reference_digits=20, min_time=0.0, backend="numpy")
    >>> [(row.method, row.setting, row.status) for row in study.rows]
    [('rk4', 'h=0.1', 0), ('rk4', 'h=0.05', 0)]
    >>> round(study.rows[0].error / study.rows[1].error, 1)
    16.0
    """
    model = system_or_model if isinstance(system_or_model, NumericModel) else _model(
        system_or_model, backend)
    model.require_inputs()
    t0, t1 = float(t_span[0]), float(t_span[1])
    if quick:
        tolerances = _QUICK_TOLERANCES
        steps = steps or [(t1 - t0) / N for N in _QUICK_DIVISIONS]
        if methods is None:
            methods = list(names(lambda m: m.quick_bench)) + _fixed_step_methods(model)
    min_time = (0.02 if quick else 0.2) if min_time is None else float(min_time)
    slow = (0.5 if quick else 20.0) if slow is None else float(slow)
    say = _say if progress else (lambda *a, **k: None)
    y_init = model.state(y0)
    y_ref, ref_error, ref_time, ref_text, digits = _reference(
        model, y_init, (t0, t1), quick, reference_digits, progress)
    if methods is None:
        methods = list(names(lambda m: m.adaptive, cheapest_first=True))
        methods += _fixed_step_methods(model)
    if steps is None:
        steps = [(t1 - t0) / N for N in _STEP_DIVISIONS]
    rows, skipped = [], []
    for method in methods:
        spec = lookup(method, key="methods")
        variants = ([False, True] if projection_variants and spec.takes_projection
                    else [False])
        for projection in variants:
            label = method + ("+projection" if projection else "")
            settings = steps if spec.fixed_step else tolerances
            too_slow = None
            for s in settings:
                text = _setting_text(method, s)
                if too_slow is not None:
                    skipped.append((label, text, too_slow))
                    continue
                say(f"  {label} {text} ...", end="")
                start = time.perf_counter()
                row = _one_row(model, y_init, (t0, t1), method, label, s, projection, y_ref,
                               repeats, loop, min_time, slow)
                rows.append(row)
                failed = "" if row.status == 0 else f"; failed: {row.status_name}"
                say(f" {1e3 * row.wall_time_s:.3g} ms (median of {row.runs} run(s){failed}; "
                    f"{time.perf_counter() - start:.2g} s)")
                if row.wall_time_s > slow or row.status == Status.TIME_LIMIT:
                    too_slow = f"{label} {text} took {row.wall_time_s:.3g} s"
    finite = [r.error for r in rows if r.status == 0 and r.error > 0]
    if finite and ref_error * 100 > min(finite):
        advice = (f"{_timed(model)}: the reference is float64 DOP853, read the "
                  "smallest errors as its own" if model.time_slot is not None else
                  "raise reference_digits" + (" (leave out --quick)" if quick else ""))
        warnings.warn(f"the reference error estimate {ref_error:.1e} is not 100 times "
                      f"below the smallest error {min(finite):.1e}; {advice}", NumericsWarning,
                      stacklevel=2)
    ratio = diagonal_ratio(model.geometry(np.array([y_init, y_ref], dtype=float))[0])
    return WorkPrecisionResult(tuple(rows), model.name, (t0, t1), digits, ref_error, ref_time,
                               model.backend, ref_text, tuple(skipped),
                               forced=model.energy_change,
                               kkt_ratio_max=float(np.nanmax(ratio)))


def _fixed_step_methods(model) -> list:
    """The fixed-step methods that take the model (RATTLE for conservative systems with L
    quadratic, the discrete gradient also with a gyroscopic term, rk4 unless the forces
    depend on time; not the Hamiltonized one, which needs the scene's reduction)."""
    linear_terms = bool(model.layout.get("linear_terms"))
    return list(names(lambda m: m.fixed_step and not m.needs_reduction
                      and (model.quadratic or not m.needs_quadratic
                           or (m.takes_gyroscopic and linear_terms))
                      and (not model.forced or m.takes_forces)
                      and (model.time_slot is None or m.takes_time)
                      and (not model.nonlinear or m.takes_nonlinear)))


def _timed(model) -> str:
    """Where the time enters, for the words about the reference of a timed system (the
    mpmath reference takes t, but at the bench's digits it would take minutes)."""
    return ("t enters L or the constraints" if model.time_in_geometry
            else "the forces depend on time")


def _say(*args, **kwargs):
    print(*args, file=sys.stderr, flush=True, **kwargs)


def _model(system, backend):
    from nhham.numerics.codegen import numeric_model

    return numeric_model(system, backend=backend)


def _reference(model, y0, t_span, quick, digits, progress):
    """(y_ref at t_end, its error estimate, wall time, description, digits)."""
    from nhham.numerics.reference import reference_solution

    say = _say if progress else (lambda *a, **k: None)
    t0, t1 = t_span
    _check_start(model, y0, t0)
    start = time.perf_counter()
    timed = model.time_slot is not None  # the mpmath reference takes autonomous fields
    if quick or timed:
        say(f"  reference: DOP853 rtol={QUICK_REFERENCE_RTOL:.0e} with projection ...", end="")
        runs = [simulate(model, t_span, y0, method=DEFAULT_METHOD, rtol=r, atol=r * 1e-3,
                         projection=True, warn=False, save_every=10**9)
                for r in (QUICK_REFERENCE_RTOL, 10 * QUICK_REFERENCE_RTOL)]
        ref, looser = runs
        if not ref.success:
            raise _reference_failure(model, ref.status, ref.message, ref.t[-1], ref.y[:, -1])
        y_ref = ref.y[:, -1]
        scale = float(np.linalg.norm(y_ref)) or 1.0
        error = (float(np.linalg.norm(looser.y[:, -1] - y_ref)) / scale if looser.success
                 else math.inf)
        why = "--quick" if quick else f"{_timed(model)}: no mpmath reference"
        text = (f"float64 DOP853 rtol={QUICK_REFERENCE_RTOL:.0e} with projection ({why}; "
                f"error estimated by a run at 10x the tolerance)")
        digits = 16
    else:
        say(f"  reference: mpmath {digits} digits (minutes on larger systems; --quick: "
            f"seconds) ...")
        ref = reference_solution(model, y0, t_span, digits=digits, t_eval=[t1],
                                 progress=progress)
        if ref.status != 0 or not len(ref.t):
            raise _reference_failure(model, ref.status, ref.message, None, None)
        y_ref, error = ref.y[:, -1], ref.error_estimate
        text = f"mpmath {digits} digits (Gragg-Bulirsch-Stoer extrapolation)"
    wall = time.perf_counter() - start
    say(f"{'' if quick else '  reference:'} {wall:.3g} s")
    return y_ref, error, wall, text, digits


def _check_start(model, y0, t0):
    """The field at the initial state: without it there is nothing to measure."""
    _, _, _, status = model.evaluate(y0)
    if status:
        raise _reference_failure(model, status, Status(status).message, t0, y0)


def _reference_failure(model, status, message, t, y) -> NumericalFailure:
    where = "" if t is None else f" at t = {t:.6g}"
    found = None if y is None else singularity_at(model, y)
    what = f": {found.describe()}" if found is not None else ""
    return NumericalFailure(status, f"the reference solution stopped{where} ({message}){what}; "
                                    f"there is nothing to measure the methods against",
                            state=None if y is None else np.array(y, dtype=float))


def _setting_text(method, setting) -> str:
    return f"h={setting:.3g}" if lookup(method).fixed_step else f"rtol={setting:.0e}"


def _one_row(model, y0, t_span, method, label, setting, projection, y_ref, repeats, loop,
             min_time, slow):
    spec = lookup(method)
    kw = {"warn": False, "projection": projection, "time_limit": 2 * slow}
    if spec.scipy_loop:
        kw["loop"] = loop
    if spec.fixed_step:
        kw["step"] = setting
        if not spec.takes_projection:
            kw.pop("projection")
    else:
        # Every step is stored so that the residual and energy columns are
        # maxima along the run (storage is outside the timed integration).
        kw.update(rtol=setting, atol=setting * 1e-3)
    times = []
    res = None
    start = time.perf_counter()
    # Like timeit's autorange: repeat until the runs (with their diagnostics) took
    # min_time, so that a sub-millisecond timing is a median of many.
    while len(times) < max(1, repeats) or time.perf_counter() - start < min_time:
        with np.errstate(all="ignore"):  # a run that blows up says so in its status
            res = simulate(model, t_span, y0, method=method, **kw)
        times.append(res.wall_time_s)
        if len(times) >= 10000:
            break
    y_end = res.y[:, -1]
    scale = float(np.linalg.norm(y_ref)) or 1.0
    err = float(np.linalg.norm(y_end - y_ref)) / scale if res.success else math.inf
    return WorkPrecisionRow(label, _setting_text(method, setting), err,
                            statistics.median(times), res.nfev, res.constraint_residual_max,
                            res.energy_drift, res.energy_balance_residual, int(res.status),
                            len(times))
