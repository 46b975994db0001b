"""Work-precision: error against a high-precision reference versus cost.

:func:`work_precision` runs every method at a ladder of settings on one
problem and measures, for each run, the error at t_end against the mpmath
reference (:mod:`nhham.numerics.reference`), the wall time, the evaluations, the
constraint residual and the energy drift. The reference must be far more
accurate than the tightest setting; its own error estimate is recorded and a
:class:`~nhham.numerics.model.NumericsWarning` is issued if it is not at least 100
times below the smallest error measured.
"""

from __future__ import annotations

import math
import statistics
import warnings
from dataclasses import asdict, dataclass

import numpy as np

from nhham.numerics.integrate import SCIPY_METHODS, simulate
from nhham.numerics.model import NumericModel, NumericsWarning

__all__ = ["WorkPrecisionRow", "WorkPrecisionResult", "work_precision", "DEFAULT_TOLERANCES"]

DEFAULT_TOLERANCES = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
_STEP_DIVISIONS = (25, 50, 100, 200, 400, 800, 1600, 3200, 6400)


@dataclass(frozen=True)
class WorkPrecisionRow:
    """One run.

    Attributes
    ----------
    method : str
        Method label (``"DOP853"``, ``"DOP853+projection"``, ``"rattle"``...).
    setting : str
        ``"rtol=1e-08"`` or ``"h=0.01"``.
    error : float
        ||y(t_end) - y_ref(t_end)||_2 / ||y_ref(t_end)||_2 (absolute if the
        reference state is zero).
    wall_time_s : float
        Median over the repeats.
    nfev : int
    constraint_residual : float
        Largest absolute constraint residual along the run.
    energy_drift : float
        max |E(t) - E(0)| along the run.
    energy_balance_residual : float
    status : int
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


@dataclass(frozen=True)
class WorkPrecisionResult:
    """Rows of a work-precision study and the reference used.

    Attributes
    ----------
    rows : tuple of WorkPrecisionRow
    name : str
    t_span : (float, float)
    reference_digits : int
    reference_error_estimate : float
    reference_wall_time_s : float
    backend : str
    """

    rows: tuple
    name: str
    t_span: tuple
    reference_digits: int
    reference_error_estimate: float
    reference_wall_time_s: float
    backend: str

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
            "reference_digits": self.reference_digits,
            "reference_error_estimate": self.reference_error_estimate,
            "reference_wall_time_s": self.reference_wall_time_s,
            "rows": self.as_dicts(),
            "time_to_solution": {"1e-06": self.time_to_solution(1e-6),
                                 "1e-10": self.time_to_solution(1e-10)},
        }

    def describe(self) -> str:
        """The table and the time to solution at relative errors 1e-6 and 1e-10."""
        lines = [f"work-precision: {self.name or 'system'}, t in {list(self.t_span)}, backend "
                 f"{self.backend}; reference: mpmath {self.reference_digits} digits "
                 f"(estimated error {self.reference_error_estimate:.1e})", "", self.table(), ""]
        for target in (1e-6, 1e-10):
            tts = self.time_to_solution(target)
            best = sorted((v, k) for k, v in tts.items() if v is not None)
            text = ", ".join(f"{k} {1e3 * v:.2f} ms" for v, k in best) or "none reached it"
            lines.append(f"time to relative error {target:.0e}: {text}")
        return "\n".join(lines)

    def table(self) -> str:
        """Markdown table of all rows."""
        head = ("| method | setting | error at t_end | wall time [ms] | evaluations | "
                "constraint residual | energy drift |\n|---|---|---|---|---|---|---|")
        lines = [head]
        for r in self.rows:
            flag = "" if r.status == 0 else f" (status {r.status})"
            lines.append(f"| {r.method} | {r.setting}{flag} | {r.error:.2e} | "
                         f"{1e3 * r.wall_time_s:.2f} | {r.nfev} | {r.constraint_residual:.1e} | "
                         f"{r.energy_drift:.1e} |")
        return "\n".join(lines)


def work_precision(system_or_model, y0, t_span, *, methods=None, tolerances=DEFAULT_TOLERANCES,
                   steps=None, projection_variants: bool = True, reference_digits: int = 30,
                   repeats: int = 1, backend: str = "auto", quick: bool = False,
                   progress: bool = False, loop: str = "auto") -> WorkPrecisionResult:
    """Run every method at every setting and measure error and cost.

    Parameters
    ----------
    system_or_model : nhham.System or NumericModel
    y0 : mapping or array_like
        A state on M_1.
    t_span : (float, float)
    methods : sequence of str, optional
        Default: every scipy method, ``"rattle"``, ``"rattle4"`` (when L is
        quadratic) and ``"rk4"``.
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
        Runs per setting; the median wall time is reported.
    quick : bool
        A small study: DOP853, Radau, LSODA and the fixed-step methods at three
        settings each, 25-digit reference.
    progress : bool
        Print each method on stderr as it starts.
    loop : {"auto", "compiled", "scipy"}
        Passed to :func:`~nhham.numerics.integrate.simulate` for the scipy methods
        (RK23, RK45 and DOP853 run as one compiled loop by default when the
        model is compiled; ``"scipy"`` measures scipy's Python loop instead).
    """
    import time

    from nhham.numerics.reference import reference_solution

    model = system_or_model if isinstance(system_or_model, NumericModel) else _model(
        system_or_model, backend)
    if quick:
        tolerances = (1e-5, 1e-8, 1e-11)
        reference_digits = min(reference_digits, 25)
        steps = steps or [(float(t_span[1]) - float(t_span[0])) / N for N in (50, 200, 800)]
        if methods is None:
            methods = ["DOP853", "Radau", "LSODA"] + (
                ["rattle", "rattle4"] if model.quadratic else []) + ["rk4"]
    t0, t1 = float(t_span[0]), float(t_span[1])
    y_init = model.state(y0)
    start = time.perf_counter()
    ref = reference_solution(model, y_init, (t0, t1), digits=reference_digits, t_eval=[t1])
    ref_time = time.perf_counter() - start
    y_ref = ref.y[:, -1]
    if methods is None:
        methods = list(SCIPY_METHODS) + (["rattle", "rattle4"] if model.quadratic else []) + ["rk4"]
    if steps is None:
        steps = [(t1 - t0) / N for N in _STEP_DIVISIONS]
    rows = []
    for method in methods:
        if progress:
            import sys

            print(f"  {method} ...", file=sys.stderr, flush=True)
        variants = [False, True] if projection_variants and method not in ("rattle",
                                                                          "rattle4") else [False]
        for projection in variants:
            label = method + ("+projection" if projection else "")
            settings = steps if method in ("rattle", "rattle4", "rk4") else tolerances
            for s in settings:
                rows.append(_one_row(model, y_init, (t0, t1), method, label, s, projection,
                                     y_ref, repeats, loop))
    finite = [r.error for r in rows if r.status == 0 and r.error > 0]
    if finite and ref.error_estimate * 100 > min(finite):
        warnings.warn(f"the reference error estimate {ref.error_estimate:.1e} is not 100 times "
                      f"below the smallest error {min(finite):.1e}; raise reference_digits",
                      NumericsWarning, stacklevel=2)
    return WorkPrecisionResult(tuple(rows), model.name, (t0, t1), reference_digits,
                               ref.error_estimate, ref_time, model.backend)


def _model(system, backend):
    from nhham.numerics.codegen import numeric_model

    return numeric_model(system, backend=backend)


def _one_row(model, y0, t_span, method, label, setting, projection, y_ref, repeats,
             loop="auto"):
    kw = {"warn": False, "projection": projection}
    if method in SCIPY_METHODS:
        kw["loop"] = loop
    if method in ("rattle", "rattle4", "rk4"):
        kw["step"] = setting
        text = f"h={setting:.3g}"
        if method != "rk4":
            kw.pop("projection")
    else:
        # Every step is stored so that the residual and energy columns are
        # maxima along the run (storage is outside the timed integration).
        kw.update(rtol=setting, atol=setting * 1e-3)
        text = f"rtol={setting:.0e}"
    times = []
    res = None
    for _ in range(max(1, repeats)):
        res = simulate(model, t_span, y0, method=method, **kw)
        times.append(res.wall_time_s)
    y_end = res.y[:, -1]
    scale = float(np.linalg.norm(y_ref)) or 1.0
    err = float(np.linalg.norm(y_end - y_ref)) / scale if res.success else math.inf
    return WorkPrecisionRow(label, text, err, statistics.median(times), res.nfev,
                            res.constraint_residual_max, res.energy_drift,
                            res.energy_balance_residual, res.status)
