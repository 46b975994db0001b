"""The IFToMM uncontrolled bicycle: three maneuvers of the benchmark bicycle, 20 s each.

The multibody community's benchmark library (IFToMM Technical Committee for Multibody
Dynamics, "Library of Computational Benchmark Problems", problem "Uncontrolled bicycle")
runs the Meijaard et al. (2007) bicycle upright from three initial forward speeds and
roll rates (:data:`MANEUVERS`), writes eight outputs every 0.01 s and measures the energy
error 100 (max E - min E)/E_0 in per cent, to be below 1e-3 %. EXUDYN's solution (J.
Gerstmayr, example ``bicycleIftommBenchmark.py``) reports 9.15e-4 % in 0.596 s (h = 0.014)
and 6.4e-6 % in 5.59 s (h = 0.001), implicit trapezoidal rule (:data:`EXUDYN`).

Set-up as EXUDYN's example makes it (the library's own description was not available to
check against): every coordinate 0 (upright, straight ahead, steer 0), the forward speed
v0 and the roll rate given, the steer rate 0, the other velocities from the rolling
constraints. The outputs (:data:`COLUMNS`): roll angle phi and rate, forward speed (the
rear contact point's speed along the heading, x' cos psi + y' sin psi; EXUDYN reads the
rear hub's velocity along the frame's axis, equal when upright), potential energy
V = -L(q, 0) (zero at the ground), kinetic energy E - V, total energy E, steer angle delta
and rate. :func:`write_results` writes a maneuver's file (time and the eight columns,
``%.15e``, one header line) and :func:`write_combined` the 25 columns of all three as
EXUDYN's ``bicycleResultsIFToMM.txt`` (time, then eight per maneuver, no header).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

import numpy as np

from nhham.numerics.methods import DEFAULT_METHOD

__all__ = ["MANEUVERS", "COLUMNS", "EXUDYN", "LIBRARY_BOUND", "ManeuverRun", "Benchmark",
           "write_results", "write_combined"]

#: The three maneuvers: initial forward speed (m/s) and roll rate (rad/s).
MANEUVERS: Mapping[str, tuple] = {"M1": (4.0, 0.05), "M2": (4.6, 0.5), "M3": (8.0, 0.05)}

#: Duration and output interval (s).
T_END, DT = 20.0, 0.01

#: The eight outputs in the library's order, with their units.
COLUMNS = ("roll angle [rad]", "roll rate [rad/s]", "forward speed [m/s]",
           "potential energy [J]", "kinetic energy [J]", "total energy [J]",
           "steer angle [rad]", "steer rate [rad/s]")

#: EXUDYN's published pairs (its example's comments): (energy error %, CPU s, step h).
EXUDYN = ((9.15e-4, 0.596, 0.014), (6.423e-6, 5.5935, 0.001))

#: The library's bound on the energy error (%).
LIBRARY_BOUND = 1e-3


@dataclass(frozen=True)
class ManeuverRun:
    """One maneuver run by nhham.

    Attributes
    ----------
    name : str
    speed, roll_rate : float
        The initial forward speed and roll rate.
    t : ndarray, shape (K,)
        Output times 0, 0.01, ..., 20.
    columns : ndarray, shape (K, 8)
        :data:`COLUMNS` at those times.
    energy_error_percent : float
        100 (max E - min E)/E_0 over the outputs.
    integration_s : float
        Wall seconds of the integration (nhham's ``wall_time_s``: the compiled loop).
    method : str
    """

    name: str
    speed: float
    roll_rate: float
    t: np.ndarray
    columns: np.ndarray
    energy_error_percent: float
    integration_s: float
    method: str


class Benchmark:
    """The bicycle's scene and compiled model, with what every run shares (the potential,
    the initial states) built once and each run (maneuver, rtol) kept."""

    def __init__(self, scene, model):
        self.scene, self.model = scene, model
        self._runs: dict = {}
        self._initial: dict = {}

    def initial_state(self, name) -> dict:
        """Maneuver ``name``'s initial state: upright, v0 and the roll rate, steer rate 0,
        the rest from the constraints."""
        from nhham.problems.measures import completed_state

        if name not in self._initial:
            speed, roll_rate = MANEUVERS[name]
            given = {c.name: 0.0 for c in self.scene.system.coordinates}
            given.update(x_dot=speed, phi_dot=roll_rate, delta_dot=0.0)
            self._initial[name] = completed_state(self.scene, given)
        return self._initial[name]

    def potential(self, Q):
        """V(q) = -L(q, 0) at the rows of Q (K, n): the model's ``potential`` kernel (written
        for an L of the form v^T W v/2 + b.v - V)."""
        model = self.model
        return model.kernels.batch("potential", np.asarray(Q, dtype=float),
                                   model.parameter_values)[:, 0]

    def run(self, name, rtol=1e-12) -> ManeuverRun:
        """Maneuver ``name`` by DOP853 at ``rtol`` (atol 1e-14): outputs every 0.01 s."""
        if (name, rtol) not in self._runs:
            self._runs[name, rtol] = self._run(name, rtol)
        return self._runs[name, rtol]

    def _run(self, name, rtol) -> ManeuverRun:
        from nhham.numerics.integrate import simulate

        speed, roll_rate = MANEUVERS[name]
        grid = np.round(np.arange(0.0, T_END + DT / 2, DT), 12)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = simulate(self.model, (0.0, T_END), self.initial_state(name),
                                    method=DEFAULT_METHOD, rtol=rtol, atol=1e-14, t_eval=grid,
                                    warn=False)
        if not result.success:
            raise RuntimeError(f"IFToMM {name}: {result.message}")
        n = self.model.n
        E = np.asarray(result.diagnostics.energy)
        Y = np.asarray(result.y)
        Y = Y.T if Y.shape[0] == 2 * n else Y
        V = np.broadcast_to(self.potential(Y[:, :n]), E.shape)
        psi = np.asarray(result["psi"])
        forward = (np.asarray(result["x_dot"]) * np.cos(psi)
                   + np.asarray(result["y_dot"]) * np.sin(psi))
        columns = np.column_stack([result["phi"], result["phi_dot"], forward, V, E - V, E,
                                   result["delta"], result["delta_dot"]])
        error = 100.0 * (E.max() - E.min()) / E[0]
        return ManeuverRun(name, speed, roll_rate, np.asarray(result.t), columns, float(error),
                           float(result.wall_time_s), f"{DEFAULT_METHOD} rtol {rtol:g}")

    def coarsest(self, bound=LIBRARY_BOUND,
                 tolerances=(1e-4, 1e-5, 1e-6, 1e-7, 1e-8)) -> dict | None:
        """The coarsest ``rtol`` of ``tolerances`` (coarsest first) at which every
        maneuver meets ``bound`` (the library's 1e-3 %): its worst error and time."""
        for rtol in tolerances:
            try:
                runs = [self.run(name, rtol) for name in MANEUVERS]
            except RuntimeError:
                continue
            if all(r.energy_error_percent <= bound for r in runs):
                return {"rtol": rtol,
                        "energy_error_percent": max(r.energy_error_percent for r in runs),
                        "integration_s": max(r.integration_s for r in runs)}
        return None


def write_results(run: ManeuverRun, path) -> Path:
    """The maneuver's results file: one header line naming the columns, then time and
    the eight columns in ``%.15e``, separated by spaces."""
    path = Path(path)
    header = (f"IFToMM uncontrolled bicycle, maneuver {run.name} (v0 = {run.speed:g} m/s, roll "
              f"rate {run.roll_rate:g} rad/s), nhham {run.method}; columns: time [s], "
              + ", ".join(COLUMNS))
    np.savetxt(path, np.column_stack([run.t, run.columns]), fmt="%.15e", header=header)
    return path


def write_combined(runs, path) -> Path:
    """The three maneuvers in one file of 25 columns (time, then eight per maneuver in
    the order M1, M2, M3), ``%1.15e`` without a header, as EXUDYN writes
    ``bicycleResultsIFToMM.txt``."""
    path = Path(path)
    np.savetxt(path, np.column_stack([runs[0].t] + [r.columns for r in runs]), fmt="%1.15e")
    return path
