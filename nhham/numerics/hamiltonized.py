"""Integration in Hamiltonized time: the reduced Chaplygin system as the canonical
Hamiltonian system it becomes after Chaplygin's change of time, then t and the group
variables reconstructed.

Where ``nhham hamiltonize`` proves a conformal factor f(r) (d(f Omega_nh) = 0,
:mod:`nhham.hamiltonian.hamiltonization`), the reduced field X satisfies
i_{X/f} (f Omega_nh) = dH_c, and f Omega_nh = dr ^ dP with P = f p: the dr ^ dr part
of f Omega_nh is linear in P, so its closedness makes it vanish. In the new time tau with
d tau = f dt the shape motion is canonical,

    dr/dtau = dH~/dP,   dP/dtau = -dH~/dr,   H~(r, P) = H_c(r, P/f(r)),

and dt/dtau = 1/f(r), dq_g/dtau = T_g(q) dr/dtau (the group coordinates q_g, from the
constraints solved for their velocities: q' = T(q) r', every reduction step composed).

One step of size h in tau is the implicit midpoint rule (symplectic and symmetric, order
2) on (r, P), Newton's method with a finite-difference Jacobian; then t1 = t0 + h/f(r_m)
and q_g1 = q_g0 + T_g(q_m) (r1 - r0) (a fixed point, q_m the midpoint): the whole step is
symmetric. The steps in tau are h = step f(r(0)) (the first ones about ``step`` in t);
the states are given on the grid t0 + k step in t, by cubic Hermite interpolation
between the steps (the derivatives from the field: order 3, above the method's 2), with
v = T(q) r' and r' = f dH~/dP: on every output state the constraints hold to rounding.

The symbolic pieces come from the journey
(:func:`nhham.journeys.hamiltonized_motion.hamiltonized_field`) as numeric functions in a
:class:`HamiltonizedField`; no sympy here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from nhham.errors import InputError
from nhham.numerics.integrators import fixed_recorder
from nhham.numerics.run import Run, report_progress
from nhham.numerics.status import NumericalFailure, Status

__all__ = ["HamiltonizedField", "hamiltonized"]


@dataclass(frozen=True)
class HamiltonizedField:
    """The numeric pieces of a Hamiltonized reduction (parameters at their values).

    Attributes
    ----------
    shape : tuple of int
        Indices of the shape coordinates r (k) in the coordinates q (n).
    group : tuple of int
        Indices of the other coordinates q_g (n - k).
    hamiltonian : callable
        ``H~(r, P)`` -> float.
    gradient : callable
        ``(r, P)`` -> (dH~/dr (k,), dH~/dP (k,)).
    factor : callable
        ``f(r)`` -> float, positive.
    lift : callable
        ``T(q)`` -> (n, k): q' = T(q) r' on M_1 (the shape rows the identity).
    momenta : callable
        ``(r, r')`` -> p (k,) = dL_c/dr'.
    factor_text : str
        f as printed (for the reports).
    """

    shape: tuple
    group: tuple
    hamiltonian: Callable
    gradient: Callable
    factor: Callable
    lift: Callable
    momenta: Callable
    factor_text: str = ""


def _midpoint(field, r0, P0, h, maxiter=30, kept=None):
    """(r1, P1, Newton iterations): the implicit midpoint rule for H~ from (r0, P0);
    ``kept`` (a dict) carries the last Jacobian from step to step (refreshed where the
    iteration stops contracting ten-fold)."""
    k = len(r0)
    z0 = np.concatenate([r0, P0])

    def residual(z):
        rm, Pm = 0.5 * (r0 + z[:k]), 0.5 * (P0 + z[k:])
        gr, gP = field.gradient(rm, Pm)
        return z - z0 - h * np.concatenate([gP, -gr])

    gr, gP = field.gradient(r0, P0)
    z = z0 + h * np.concatenate([gP, -gr])
    scale = 1.0 + np.abs(z0)
    kept = {} if kept is None else kept
    best, J = np.inf, kept.get("J")
    for it in range(maxiter):
        r = residual(z)
        err = float(np.max(np.abs(r) / scale))
        if not math.isfinite(err):
            raise NumericalFailure(Status.NONFINITE, "non-finite residual in the implicit "
                                   "midpoint step of the Hamiltonized field")
        if err <= 2 * np.finfo(float).eps or (it > 3 and err >= best and err < 1e-12):
            return z[:k], z[k:], it
        if J is None or err > 0.1 * best:
            e = np.sqrt(np.finfo(float).eps) * np.maximum(np.abs(z), scale)
            J = np.column_stack([(residual(z + np.eye(2 * k)[j] * e[j]) - r) / e[j]
                                 for j in range(2 * k)])
            kept["J"] = J
        best = min(best, err)
        z = z - np.linalg.solve(J, r)
    raise NumericalFailure(Status.NOT_CONVERGED, f"the implicit midpoint step did not "
                           f"converge (residual {err:.3g}); reduce the step")


def _group_step(field, q0, r1, maxiter=50):
    """q1: q_g1 = q_g0 + T_g(q_m) (r1 - r0) by fixed-point iteration, the shape rows r1."""
    shape, group = list(field.shape), list(field.group)
    q1 = q0.copy()
    q1[shape] = r1
    dr = r1 - q0[shape]
    for _ in range(maxiter):
        new = q0[group] + field.lift(0.5 * (q0 + q1))[group] @ dr
        done = np.max(np.abs(new - q1[group]), initial=0.0) <= 2 * np.finfo(float).eps * (
            1.0 + np.max(np.abs(new), initial=0.0))
        q1[group] = new
        if done:
            return q1
    raise NumericalFailure(Status.NOT_CONVERGED, "the reconstruction of the group "
                           "coordinates did not converge; reduce the step")


def _velocities(field, q, P):
    """v = T(q) r' with r' = f dH~/dP: the state's velocities, and dP/dt."""
    r = q[list(field.shape)]
    f = field.factor(r)
    gr, gP = field.gradient(r, P)
    rdot = f * gP
    return field.lift(q) @ rdot, -f * gr


def hamiltonized(model, y0, t0, t1, h, *, reduced=None, save_every: int = 1, recorder=None,
                 progress: bool = False, deadline=None) -> Run:
    """Integrate in Hamiltonized time (module docstring) and give the states on the grid
    t0 + j h in t.

    Parameters
    ----------
    model : NumericModel
        The whole system (its n; the diagnostics read it).
    y0 : ndarray, shape (2n,)
        A state on M_1.
    t0, t1, h : float
        Interval and step in t of the output grid (the steps in tau are h f(r(0))).
    reduced : HamiltonizedField
        The Hamiltonized reduction (required).
    save_every, recorder, progress, deadline
        As :func:`nhham.numerics.integrators.rattle`.

    Returns
    -------
    Run
        The states on the grid; ``nsteps`` the steps in tau, ``newton_iterations`` the
        midpoint rule's.
    """
    if reduced is None:
        raise InputError("method 'hamiltonized' needs the Hamiltonized reduction: run it "
                         "on a scene (nhham simulate SCENE --method hamiltonized)",
                         key="method")
    if not (h > 0 and math.isfinite(h)):
        raise InputError(f"step: a positive finite step is required, got {h!r}")
    if not t1 > t0:   # Chaplygin's time runs with t: backwards would need f's sign turned
        raise InputError(f"t_span: method 'hamiltonized' integrates forward in t, got "
                         f"({t0!r}, {t1!r})", key="t_span")
    field, n = reduced, model.n
    shape = list(field.shape)
    N = max(1, int(math.ceil((t1 - t0) / h - 1e-9)))
    grid = t0 + (t1 - t0) * np.arange(N + 1) / N
    recorder = fixed_recorder(recorder, 2 * n, save_every)
    q, v = np.array(y0[:n], dtype=float), np.array(y0[n:], dtype=float)
    r = q[shape]
    P = field.factor(r) * np.asarray(field.momenta(r, v[shape]), dtype=float)
    htau = h * field.factor(r)
    v_now, dP_now = _velocities(field, q, P)
    t, j, steps, newton, reported = t0, 0, 0, 0, 0
    jacobian: dict = {}   # the midpoint rule's last Jacobian, kept from step to step
    status, message = Status.SUCCESS, Status.SUCCESS.message
    try:
        while j <= N:
            # grid points up to this step's end: cubic Hermite between (t, q, P) and the next
            r1, P1, it = _midpoint(field, q[shape], P, htau, kept=jacobian)
            q1 = _group_step(field, q, r1)
            t_next = t + htau / field.factor(0.5 * (q[shape] + r1))
            v1, dP1 = _velocities(field, q1, P1)
            steps, newton = steps + 1, newton + it
            while j <= N and (grid[j] <= t_next or j == 0):
                if not (recorder.keep(j) or j == N):   # only the states kept are formed
                    j += 1
                    continue
                s = (grid[j] - t) / (t_next - t)
                dt = t_next - t
                h00, h10 = 2 * s ** 3 - 3 * s ** 2 + 1, s ** 3 - 2 * s ** 2 + s
                h01, h11 = -2 * s ** 3 + 3 * s ** 2, s ** 3 - s ** 2
                qj = h00 * q + h10 * dt * v_now + h01 * q1 + h11 * dt * v1
                Pj = h00 * P + h10 * dt * dP_now + h01 * P1 + h11 * dt * dP1
                vj = _velocities(field, qj, Pj)[0]
                y_last, j = np.concatenate([qj, vj]), j + 1
                if j - 1 < N:
                    recorder.add(float(grid[j - 1]), y_last)
            q, P, t, v_now, dP_now = q1, P1, t_next, v1, dP1
            if progress:
                reported = report_progress(min(t, t1), t0, t1, reported)
            if deadline is not None and j <= N and deadline.passed():
                status, message = deadline.stop_status(), deadline.message(t)
                break
    except NumericalFailure as exc:
        status, message = exc.status, str(exc)
    except np.linalg.LinAlgError as exc:
        status, message = Status.SINGULAR, f"singular linear system at t = {t:.6g}: {exc}"
    if j:
        recorder.close(float(grid[j - 1]), y_last)
    T, Y, _ = recorder.result(2 * n)
    return Run(T, Y, None, status, message, steps * 4 + newton, steps,
               newton_iterations=newton, step=htau)
