"""An independent reference integrator for the snakeboard driven by torques.

The system is the one of ``examples/snakeboard.toml``: q = (x, y, theta, psi, phi),
parameters m, J, J_r, J_w, r, the Lagrangian

    L = m (x'^2 + y'^2)/2 + J theta'^2/2 + J_r (theta' + psi')^2/2
        + J_w ((theta' + phi')^2 + (theta' - phi')^2)/2

and the no-slip constraints mu(q) q' = 0 of the front axle (along theta + phi, r ahead
of the centre) and the back axle (along theta - phi, r behind). A rotor torque u_psi(t) acts on psi and a steering torque u_phi(t) on phi, so the
generalized forces are Q = (0, 0, 0, u_psi, u_phi).

The mass matrix M is constant and there is no potential, so the equations of motion
are the KKT system

    [[M, mu^T], [mu, 0]] [q''; lambda] = [Q; -(d mu/dt) q'],

solved here with ``numpy.linalg.solve`` and integrated with scipy's DOP853. Everything
(M, mu, d mu/dt) is written out by hand; nothing from nhham is used, so the module can
serve as an independent reference in the tests.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

PARAMS = {"m": 1.0, "J": 0.3333333333333333, "J_r": 0.2, "J_w": 0.05, "r": 1.0}


def mass_matrix(params=None):
    """The constant mass matrix M of the Lagrangian, shape (5, 5); ``params=None``: PARAMS."""
    p = PARAMS if params is None else params
    m, J, J_r, J_w = p["m"], p["J"], p["J_r"], p["J_w"]
    M = np.zeros((5, 5))
    M[0, 0] = M[1, 1] = m
    M[2, 2] = J + J_r + 2.0 * J_w
    M[2, 3] = M[3, 2] = M[3, 3] = J_r
    M[4, 4] = 2.0 * J_w
    return M


def constraint_matrix(q, params=None):
    """The constraint matrix mu(q), shape (2, 5), with the constraints mu(q) q' = 0."""
    r = (PARAMS if params is None else params)["r"]
    _, _, th, _, ph = q
    return np.array([
        [-np.sin(th + ph), np.cos(th + ph), r * np.cos(ph), 0.0, 0.0],
        [-np.sin(th - ph), np.cos(th - ph), -r * np.cos(ph), 0.0, 0.0],
    ])


def constraint_rate(q, v, params=None):
    """The vector (d mu/dt) q' along the velocity ``v``, shape (2,)."""
    r = (PARAMS if params is None else params)["r"]
    _, _, th, _, ph = q
    xd, yd, thd, _, phd = v
    front = np.cos(th + ph) * xd + np.sin(th + ph) * yd
    back = np.cos(th - ph) * xd + np.sin(th - ph) * yd
    spin = r * np.sin(ph) * phd * thd
    return np.array([-(thd + phd) * front - spin, -(thd - phd) * back + spin])


def accelerations(t, q, v, params, torque):
    """Accelerations q'' and multipliers lambda from the KKT system at time ``t``.

    Parameters
    ----------
    t : float
    q, v : array_like, shape (5,)
    params : dict or None
        Values of m, J, J_r, J_w, r (``None``: PARAMS).
    torque : callable
        ``torque(t) -> (u_psi, u_phi)``.

    Returns
    -------
    a, lam : ndarray, shapes (5,) and (2,)
    """
    u_psi, u_phi = torque(t)
    mu = constraint_matrix(q, params)
    K = np.zeros((7, 7))
    K[:5, :5] = mass_matrix(params)
    K[:5, 5:] = mu.T
    K[5:, :5] = mu
    rhs = np.concatenate([[0.0, 0.0, 0.0, u_psi, u_phi], -constraint_rate(q, v, params)])
    sol = np.linalg.solve(K, rhs)
    return sol[:5], sol[5:]


def energy(v, params=None):
    """The kinetic energy v^T M v / 2 (the Lagrangian has no potential)."""
    v = np.asarray(v)
    return 0.5 * v @ mass_matrix(params) @ v


def integrate_with_work(y0, t_end, params, torque, rtol=1e-12, atol=1e-12):
    """Integrate from t = 0 to ``t_end``; return the final state (10,) and the work of Q.

    The work int_0^t_end Q . v dt is carried as an eleventh state, so that
    E(t_end) - E(0) - work measures the error of the integration.
    """
    def rhs(t, y):
        a, _ = accelerations(t, y[:5], y[5:10], params, torque)
        u_psi, u_phi = torque(t)
        return np.concatenate([y[5:10], a, [u_psi * y[8] + u_phi * y[9]]])

    y_start = np.concatenate([np.asarray(y0, dtype=float), [0.0]])
    sol = solve_ivp(rhs, (0.0, t_end), y_start, method="DOP853", rtol=rtol, atol=atol)
    if not sol.success:
        raise RuntimeError(sol.message)
    return sol.y[:10, -1], sol.y[10, -1]


def integrate(y0, t_end, params, torque, rtol=1e-12, atol=1e-12):
    """Integrate y = (q, v) from t = 0 to ``t_end`` with DOP853; return the final state (10,)."""
    return integrate_with_work(y0, t_end, params, torque, rtol, atol)[0]


def gait(t, a_psi=0.5, a_phi=0.3, omega=2 * np.pi):
    """A smooth gait of period 2 pi/omega: (a_psi sin(omega t), a_phi cos(omega t))."""
    return a_psi * np.sin(omega * t), a_phi * np.cos(omega * t)


def rest_state(phi=0.2):
    """At rest at the origin with steering angle ``phi`` (on the constraint manifold)."""
    y0 = np.zeros(10)
    y0[4] = phi
    return y0


def net_displacement(params=None, period=1.0, y0=None, torque=gait):
    """The change of (x, y, theta) over one ``period`` of ``torque`` from ``y0``.

    ``y0=None`` starts from ``rest_state()`` (all zero but phi = 0.2, not the
    degenerate phi = +-pi/2); returns an ndarray of shape (3,).
    """
    y0 = rest_state() if y0 is None else np.asarray(y0, dtype=float)
    return integrate(y0, period, params, torque)[:3] - y0[:3]


if __name__ == "__main__":
    import time

    start = time.perf_counter()
    yT, work = integrate_with_work(y0 := rest_state(), 1.0, None, gait)
    elapsed = time.perf_counter() - start
    print("net displacement (x, y, theta):", repr(yT[:3] - y0[:3]))
    print("constraint residual |mu(q) v|:", np.abs(constraint_matrix(yT[:5]) @ yT[5:]).max())
    print("energy balance E(T) - E(0) - W:", energy(yT[5:]) - energy(y0[5:]) - work)
    print(f"run time: {elapsed:.3f} s")
