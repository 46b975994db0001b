"""Numerical trajectories against closed-form solutions derived by hand.

Every system is built here with :class:`nhham.System` (independent of
``nhham.models``); every reference value comes from the closed form in the
docstring of its builder, never from another integrator. The builders are
reused by the other numerics tests.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import nhham
from nhham.numerics.codegen import numeric_model
from nhham.numerics.integrate import simulate

# ----------------------------------------------------------------- systems


def rolling_disk(m=1.3, I1=0.5, I2=0.25, R=0.7):
    """Vertical rolling disk: L = m/2 (x'^2 + y'^2) + I1/2 th'^2 + I2/2 ph'^2,
    x' = R cos(th) ph', y' = R sin(th) ph'.

    Closed form: the constraint forces act at the contact point in the plane,
    so th'' = 0 and (I2 + m R^2) ph'' = 0: th = th0 + w t, ph' = s constant,
    x = x0 + (R s / w)(sin th - sin th0), y = y0 - (R s / w)(cos th - cos th0);
    m x'' = -lambda_1 gives lambda = m R w s (sin th, -cos th).
    """
    xd, yd, thd, phd = sp.symbols("x_dot y_dot theta_dot phi_dot")
    th = sp.Symbol("theta")
    mm, i1, i2, r = sp.symbols("m I1 I2 R")
    L = mm * (xd**2 + yd**2) / 2 + i1 * thd**2 / 2 + i2 * phd**2 / 2
    return nhham.System(["x", "y", "theta", "phi"], L,
                        [xd - r * sp.cos(th) * phd, yd - r * sp.sin(th) * phd],
                        parameters={"m": m, "I1": I1, "I2": I2, "R": R}, name="rolling disk")


def rolling_disk_exact(t, x0=0.2, y0=-0.1, th0=0.3, ph0=0.0, w=1.1, s=2.0, R=0.7, m=1.3):
    th = th0 + w * t
    x = x0 + R * s / w * (np.sin(th) - np.sin(th0))
    y = y0 - R * s / w * (np.cos(th) - np.cos(th0))
    ph = ph0 + s * t
    state = np.array([x, y, th, ph, R * s * np.cos(th), R * s * np.sin(th),
                      np.full_like(th, w), np.full_like(th, s)])
    lam = np.array([m * R * w * s * np.sin(th), -m * R * w * s * np.cos(th)])
    return state, lam


def chaplygin_sleigh(m=1.0, I=0.3, a=0.5):
    """Chaplygin sleigh in centre-of-mass coordinates (x, y, theta); the blade
    (contact point) is at distance a behind the centre of mass along the body
    axis e1 = (cos th, sin th); it cannot slide along e2:
    -sin(th) x' + cos(th) y' - a th' = 0.

    Body velocities u = e1 . (x', y') and w = th' obey m u' = m a w^2 and
    (I + m a^2) w' = -m a u w (Newton along e1, torque about G of the blade
    force -a F). With J = I + m a^2, U = sqrt(2E/m) (E = m u^2/2 + J w^2/2),
    k = a m U / J, c = atanh(u0/U):
    u = U tanh(k t + c), w = sign(w0) sqrt(m/J) U sech(k t + c),
    th = th0 + sign(w0) sqrt(m/J) (U/k) (gd(k t + c) - gd(c)), gd = 2 atan(tanh(x/2)).
    """
    xd, yd, thd = sp.symbols("x_dot y_dot theta_dot")
    th = sp.Symbol("theta")
    mm, ii, aa = sp.symbols("m I a")
    L = mm * (xd**2 + yd**2) / 2 + ii * thd**2 / 2
    return nhham.System(["x", "y", "theta"], L, [-sp.sin(th) * xd + sp.cos(th) * yd - aa * thd],
                        parameters={"m": m, "I": I, "a": a}, name="Chaplygin sleigh")


def sleigh_state(th0=0.3, u0=0.4, w0=1.5, a=0.5):
    e1 = np.array([math.cos(th0), math.sin(th0)])
    e2 = np.array([-math.sin(th0), math.cos(th0)])
    v = u0 * e1 + a * w0 * e2
    return np.array([0.0, 0.0, th0, v[0], v[1], w0])


def sleigh_exact(t, th0=0.3, u0=0.4, w0=1.5, m=1.0, I=0.3, a=0.5):
    J = I + m * a * a
    U = math.sqrt(u0**2 + J * w0**2 / m)
    k = a * m * U / J
    c = math.atanh(u0 / U)
    s = k * t + c
    gd = lambda x: 2 * np.arctan(np.tanh(x / 2))  # noqa: E731
    u = U * np.tanh(s)
    w = math.copysign(1.0, w0) * math.sqrt(m / J) * U / np.cosh(s)
    th = th0 + math.copysign(1.0, w0) * math.sqrt(m / J) * (U / k) * (gd(s) - gd(c))
    return u, w, th


def nonholonomic_particle(potential=0):
    """Particle in R^3 with z' = y x' (the "nonholonomic particle").

    potential=0: free. Then y'' = 0 (y = y0 + b t), x'' = lambda y,
    z'' = -lambda with z'' = y' x' + y x'' gives lambda = -x' y'/(1 + y^2), so
    x' sqrt(1 + y^2) = c is constant and
    x = x0 + (c/b)(asinh y - asinh y0), z = z0 + (c/b)(sqrt(1+y^2) - sqrt(1+y0^2)).
    potential="harmonic": V = (x^2 + y^2)/2 (reversible test problem);
    potential="y-harmonic": V = y^2/2 (y'' = -y exactly).
    """
    xd, yd, zd = sp.symbols("x_dot y_dot z_dot")
    x, y = sp.symbols("x y")
    L = (xd**2 + yd**2 + zd**2) / 2
    if potential == "harmonic":
        L = L - (x**2 + y**2) / 2
    elif potential == "y-harmonic":
        L = L - y**2 / 2
    return nhham.System(["x", "y", "z"], L, [zd - y * xd], name="nonholonomic particle")


def particle_exact(t, x0=0.1, y0=-0.5, z0=0.2, xd0=1.2, b=0.7):
    c = xd0 * math.sqrt(1 + y0**2)
    y = y0 + b * t
    x = x0 + c / b * (np.arcsinh(y) - math.asinh(y0))
    z = z0 + c / b * (np.sqrt(1 + y**2) - math.sqrt(1 + y0**2))
    xd = c / np.sqrt(1 + y**2)
    return np.array([x, y, z, xd, np.full_like(y, b), y * xd])


def knife_edge(m=2.0, J=0.3, g=9.81, alpha=0.4):
    """Knife edge on a plane inclined at alpha, x down the slope:
    L = m/2 (x'^2 + y'^2) + J/2 phi'^2 + m g sin(alpha) x, sin(phi) x' - cos(phi) y' = 0.

    The blade force has no moment about the contact point: phi = phi0 + w t.
    With s the speed along the blade (x' = s cos phi, y' = s sin phi),
    m s' = m g sin(alpha) cos(phi): s = s0 + A (sin phi - sin phi0), A = g sin(alpha)/w,
    x = x0 + (s0 - A sin phi0)(sin phi - sin phi0)/w + A (sin^2 phi - sin^2 phi0)/(2w),
    y = y0 + (s0 - A sin phi0)(cos phi0 - cos phi)/w
           + A [t/2 - (sin 2phi - sin 2phi0)/(4w)].
    """
    xd, yd, phd = sp.symbols("x_dot y_dot phi_dot")
    x, ph = sp.symbols("x phi")
    mm, jj, gg, al = sp.symbols("m J g alpha")
    L = mm * (xd**2 + yd**2) / 2 + jj * phd**2 / 2 + mm * gg * sp.sin(al) * x
    return nhham.System(["x", "y", "phi"], L, [sp.sin(ph) * xd - sp.cos(ph) * yd],
                        parameters={"m": m, "J": J, "g": g, "alpha": alpha},
                        name="knife edge on an inclined plane")


def knife_exact(t, x0=0.0, y0=0.0, ph0=0.2, w=1.3, s0=0.5, g=9.81, alpha=0.4):
    A = g * math.sin(alpha) / w
    ph = ph0 + w * t
    s = s0 + A * (np.sin(ph) - math.sin(ph0))
    B = s0 - A * math.sin(ph0)
    x = x0 + B * (np.sin(ph) - math.sin(ph0)) / w + A * (np.sin(ph)**2 - math.sin(ph0)**2) / (2 * w)
    y = y0 + B * (math.cos(ph0) - np.cos(ph)) / w + A * (
        t / 2 - (np.sin(2 * ph) - math.sin(2 * ph0)) / (4 * w))
    return np.array([x, y, ph, s * np.cos(ph), s * np.sin(ph), np.full_like(ph, w)])


def ball_on_turntable(m=1.0, r=2.0, Omega=3.0):
    """Homogeneous ball (I = 2/5 m r^2) rolling on a table turning at Omega
    about the vertical axis through the origin; orientation by ZXZ Euler
    angles (phi, theta, psi), space angular velocity
    w = (th' cos phi + psi' sin th sin phi, th' sin phi - psi' sin th cos phi,
    phi' + psi' cos th). The contact point moves with the table:
    x' - r w_y + Omega y = 0,  y' + r w_x - Omega x = 0 (affine).

    Closed form: m x'' = F_x, I w_y' = -r F_x, I w_x' = r F_y, w_z' = 0; the
    derivative of the constraints gives x'' = -(2/7) Omega y', y'' = (2/7) Omega x':
    the centre's velocity turns at kappa = 2 Omega/7, so with zeta = x + i y,
    zeta = zeta0 + V0 (exp(i kappa t) - 1)/(i kappa), V0 = x0' + i y0'. E is not
    conserved (|w| changes); dE/dt = lambda . h.
    """
    xd, yd, phd, thd, psd = sp.symbols("x_dot y_dot phi_dot theta_dot psi_dot")
    x, y, ph, th = sp.symbols("x y phi theta")
    mm, rr, Om = sp.symbols("m r Omega")
    I = sp.Rational(2, 5) * mm * rr**2
    wx = thd * sp.cos(ph) + psd * sp.sin(th) * sp.sin(ph)
    wy = thd * sp.sin(ph) - psd * sp.sin(th) * sp.cos(ph)
    wz = phd + psd * sp.cos(th)
    L = mm * (xd**2 + yd**2) / 2 + I * (wx**2 + wy**2 + wz**2) / 2
    return nhham.System(["x", "y", "phi", "theta", "psi"], sp.expand(sp.simplify(L)),
                        [xd - rr * wy + Om * y, yd + rr * wx - Om * x],
                        parameters={"m": m, "r": r, "Omega": Omega}, name="ball on turntable")


def ball_state(model, x0=0.3, y0=-0.2, vx=0.4, vy=0.1, th0=1.5, ph0=0.4, phd=0.25, r=2.0,
               Omega=3.0):
    """A point of M_1: choose x, y, their velocities, the Euler angles and phi';
    solve the constraints for (theta', psi') by hand. The defaults keep the
    orientation far from the Euler-angle singularity sin(theta) = 0 over a
    period (the ball turns by less than a radian)."""
    # w_x = (Omega x - y')/r, w_y = (x' + Omega y)/r.
    wx, wy = (Omega * x0 - vy) / r, (vx + Omega * y0) / r
    s, c = math.sin(ph0), math.cos(ph0)
    st = math.sin(th0)
    # [cos ph, sin th sin ph; sin ph, -sin th cos ph] [th'; psi'] = [wx; wy] with psi' given:
    # th' from the combination cos ph * wx + sin ph * wy = th'.
    thd = c * wx + s * wy
    psd_ = (s * wx - c * wy) / st
    return model.state({"x": x0, "y": y0, "phi": ph0, "theta": th0, "psi": 0.0,
                        "x_dot": vx, "y_dot": vy, "phi_dot": phd, "theta_dot": thd,
                        "psi_dot": psd_})


def ball_exact(t, x0=0.3, y0=-0.2, vx=0.4, vy=0.1, Omega=3.0):
    kappa = 2 * Omega / 7
    V0 = vx + 1j * vy
    zeta = (x0 + 1j * y0) + V0 * (np.exp(1j * kappa * t) - 1) / (1j * kappa)
    vel = V0 * np.exp(1j * kappa * t)
    return zeta.real, zeta.imag, vel.real, vel.imag


# ------------------------------------------------------------------- tests
ADAPTIVE = ["RK45", "DOP853", "Radau", "BDF", "LSODA"]


@pytest.fixture(scope="module")
def disk_model():
    return numeric_model(rolling_disk())


@pytest.mark.parametrize("method", ADAPTIVE + ["RK23"])
def test_rolling_disk_every_scipy_method(disk_model, method):
    """All scipy methods on the rolling disk, without and with projection."""
    ex0, _ = rolling_disk_exact(np.array(0.0))
    t = np.linspace(0, 6, 13)
    exact, _ = rolling_disk_exact(t)
    for projection in (False, True):
        res = simulate(disk_model, (0, 6), ex0, method=method, rtol=1e-10, atol=1e-12,
                       t_eval=t, projection=projection, warn=False)
        assert res.success, res.message
        err = np.max(np.abs(res.y - exact))
        assert err < (1e-5 if method == "RK23" else 2e-7), (method, projection, err)
        if projection:
            assert res.constraint_residual_max <= 1e-12
        assert res.energy_drift < 1e-6


def test_rolling_disk_multipliers_match_closed_form(disk_model):
    t = np.linspace(0, 3, 7)
    exact, lam = rolling_disk_exact(t)
    res = simulate(disk_model, (0, 3), exact[:, 0], t_eval=t, rtol=1e-11, atol=1e-13, warn=False)
    assert np.max(np.abs(res.multipliers - lam)) < 1e-8


@pytest.mark.parametrize("method,step,tol", [("rattle", 0.01, 2e-4), ("rattle4", 0.02, 1e-6),
                                             ("rk4", 0.01, 1e-7)])
def test_rolling_disk_fixed_step(disk_model, method, step, tol):
    ex0, _ = rolling_disk_exact(np.array(0.0))
    res = simulate(disk_model, (0, 6), ex0, method=method, step=step, warn=False)
    exact, _ = rolling_disk_exact(res.t)
    assert res.success
    assert np.max(np.abs(res.y - exact)) < tol
    if method != "rk4":
        assert res.constraint_residual_max <= 1e-12


@pytest.mark.parametrize("method,kw,tol", [
    ("DOP853", {"rtol": 1e-11, "atol": 1e-13}, 1e-8),
    ("Radau", {"rtol": 1e-10, "atol": 1e-12}, 1e-7),
    ("DOP853", {"rtol": 1e-11, "atol": 1e-13, "projection": True}, 1e-8),
    ("rattle", {"step": 0.005}, 1e-4),
    ("rattle4", {"step": 0.02}, 1e-6),
])
def test_chaplygin_sleigh_closed_form(method, kw, tol):
    """u(t), w(t), th(t) against the tanh/sech closed form."""
    model = numeric_model(chaplygin_sleigh())
    t_end = 8.0
    res = simulate(model, (0, t_end), sleigh_state(), method=method, warn=False, **kw)
    assert res.success, res.message
    th, xd, yd, w = res["theta"], res["x_dot"], res["y_dot"], res["theta_dot"]
    u_num = np.cos(th) * xd + np.sin(th) * yd
    u, w_ex, th_ex = sleigh_exact(res.t)
    err = max(np.max(np.abs(u_num - u)), np.max(np.abs(w - w_ex)), np.max(np.abs(th - th_ex)))
    assert err < tol, err
    assert res.energy_drift < max(10 * tol, 1e-9)


@pytest.mark.parametrize("method,kw,tol", [
    ("DOP853", {"rtol": 1e-11, "atol": 1e-13}, 1e-8),
    ("LSODA", {"rtol": 1e-10, "atol": 1e-12, "projection": True}, 1e-6),
    ("rattle", {"step": 0.005}, 1e-4),
    ("rk4", {"step": 0.01, "projection": True}, 1e-7),
])
def test_nonholonomic_particle_closed_form(method, kw, tol):
    model = numeric_model(nonholonomic_particle())
    y0 = particle_exact(np.array(0.0))
    res = simulate(model, (0, 5.0), y0, method=method, warn=False, **kw)
    assert res.success
    err = np.max(np.abs(res.y - particle_exact(res.t)))
    assert err < tol, err


@pytest.mark.parametrize("method,kw,tol", [
    ("DOP853", {"rtol": 1e-11, "atol": 1e-13}, 1e-8),
    ("BDF", {"rtol": 1e-9, "atol": 1e-11, "projection": True}, 1e-5),
    ("rattle", {"step": 0.002}, 2e-4),
    ("rattle4", {"step": 0.01}, 1e-6),
])
def test_knife_edge_inclined_closed_form(method, kw, tol):
    model = numeric_model(knife_edge())
    y0 = knife_exact(np.array(0.0))
    res = simulate(model, (0, 4.0), y0, method=method, warn=False, **kw)
    assert res.success
    exact = knife_exact(res.t)
    scale = 1 + np.max(np.abs(exact))
    assert np.max(np.abs(res.y - exact)) / scale < tol
    assert res.energy_drift / (1 + abs(res.energy[0])) < 10 * tol


@pytest.mark.parametrize("method,kw,tol", [
    ("DOP853", {"rtol": 1e-11, "atol": 1e-13}, 1e-8),
    ("Radau", {"rtol": 1e-10, "atol": 1e-12, "projection": True}, 1e-6),
    ("rattle", {"step": 0.01}, 1e-4),
])
def test_ball_on_turntable_circle(method, kw, tol):
    """The centre turns at 2 Omega/7; energy is not conserved, the balance
    dE/dt = lambda . h holds."""
    model = numeric_model(ball_on_turntable())
    y0 = ball_state(model)
    period = 2 * math.pi / (2 * 3.0 / 7)
    res = simulate(model, (0, period), y0, method=method, warn=False, **kw)
    assert res.success, res.message
    x, y, vx, vy = ball_exact(res.t)
    err = max(np.max(np.abs(res["x"] - x)), np.max(np.abs(res["y"] - y)),
              np.max(np.abs(res["x_dot"] - vx)), np.max(np.abs(res["y_dot"] - vy)))
    assert err < tol, err
    # after one period of 2 Omega/7 the centre is back where it started
    assert abs(res["x"][-1] - 0.3) < 10 * tol and abs(res["y"][-1] + 0.2) < 10 * tol
    assert res.energy_drift > 1e-3  # not conserved ...
    assert res.energy_balance_residual < 100 * tol  # ... but balanced by the work of lambda
    if method == "rattle" or kw.get("projection"):
        assert res.constraint_residual_max <= 1e-12
