"""Systems written out by hand for the tests, with hand-built points of M_1.

Each entry gives the System and a function that returns a random point of
M_1 (coordinates, velocities and parameter values) built by solving the
constraints by hand, so that identities can be checked numerically without
the library's own reduction.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

import nhham

S = sp.Symbol


def rolling_disk(params=True):
    x, y, th, ph = sp.symbols("x y theta phi")
    xd, yd, thd, phd = sp.symbols("x_dot y_dot theta_dot phi_dot")
    m, I1, I2, R = sp.symbols("m I1 I2 R")
    L = m * (xd**2 + yd**2) / 2 + I1 * thd**2 / 2 + I2 * phd**2 / 2
    values = {"m": 1.3, "I1": 0.5, "I2": 0.25, "R": 0.7} if params else ["m", "I1", "I2", "R"]
    system = nhham.System(["x", "y", "theta", "phi"], L,
                          [xd - R * sp.cos(th) * phd, yd - R * sp.sin(th) * phd],
                          parameters=values, name="rolling disk")

    def point(rng):
        p = {x: rng.normal(), y: rng.normal(), th: rng.uniform(-3, 3), ph: rng.normal(),
             thd: rng.normal(), phd: rng.normal(),
             m: 1.3, I1: 0.5, I2: 0.25, R: 0.7}
        p[xd] = p[R] * np.cos(p[th]) * p[phd]
        p[yd] = p[R] * np.sin(p[th]) * p[phd]
        return p

    return system, point


def knife_edge_inclined():
    """Knife edge on a plane inclined at angle alpha; x down the slope."""
    x, y, ph = sp.symbols("x y phi")
    xd, yd, phd = sp.symbols("x_dot y_dot phi_dot")
    m, J, g, al = sp.symbols("m J g alpha")
    L = m * (xd**2 + yd**2) / 2 + J * phd**2 / 2 + m * g * sp.sin(al) * x
    system = nhham.System(["x", "y", "phi"], L, [sp.sin(ph) * xd - sp.cos(ph) * yd],
                          parameters={"m": 2.0, "J": 0.3, "g": 9.81, "alpha": 0.4},
                          name="knife edge on an inclined plane")

    def point(rng):
        p = {x: rng.normal(), y: rng.normal(), ph: rng.uniform(-3, 3), phd: rng.normal(),
             m: 2.0, J: 0.3, g: 9.81, al: 0.4}
        s = rng.normal()  # speed along the blade
        p[xd], p[yd] = s * np.cos(p[ph]), s * np.sin(p[ph])
        return p

    return system, point


def chaplygin_sleigh():
    """Sleigh: centre of mass (x, y), heading theta, blade at distance a behind."""
    x, y, th = sp.symbols("x y theta")
    xd, yd, thd = sp.symbols("x_dot y_dot theta_dot")
    m, I, a = sp.symbols("m I a")
    L = m * (xd**2 + yd**2) / 2 + I * thd**2 / 2
    # Blade point (x - a cos th, y - a sin th) moves along the heading only.
    phi = -sp.sin(th) * xd + sp.cos(th) * yd + a * thd
    system = nhham.System(["x", "y", "theta"], L, [phi],
                          parameters={"m": 1.5, "I": 0.4, "a": 0.6}, name="Chaplygin sleigh")

    def point(rng):
        p = {x: rng.normal(), y: rng.normal(), th: rng.uniform(-3, 3), thd: rng.normal(),
             m: 1.5, I: 0.4, a: 0.6}
        u = rng.normal()  # forward speed
        w = -p[a] * p[thd]  # lateral speed of the centre: -sin xd + cos yd = -a thd
        p[xd] = u * np.cos(p[th]) - w * np.sin(p[th])
        p[yd] = u * np.sin(p[th]) + w * np.cos(p[th])
        return p

    return system, point


def two_particle_rod():
    """Paper Example 4.1 with P1 = (x1, y1), P2 = (x2, y2), unit masses."""
    x1, x2, y1, y2 = sp.symbols("x1 x2 y1 y2")
    x1d, x2d, y1d, y2d = sp.symbols("x1_dot x2_dot y1_dot y2_dot")
    g, l = sp.symbols("g l")
    L = (x1d**2 + x2d**2 + y1d**2 + y2d**2) / 2 - g * (y1 + y2)
    h1 = ((x2 - x1) ** 2 + (y2 - y1) ** 2 - l**2) / 2
    phi2 = (x2 - x1) * (y2d + y1d) - (x2d + x1d) * (y2 - y1)
    system = nhham.System(["x1", "x2", "y1", "y2"], L, [phi2], holonomic=[h1],
                          parameters={"g": 9.81, "l": 1.2}, name="two-particle rod")

    def point(rng):
        lv = 1.2
        a = rng.uniform(-3, 3)
        cx, cy = rng.normal(), rng.normal()
        ux, uy = np.cos(a), np.sin(a)
        p = {x1: cx - lv / 2 * ux, x2: cx + lv / 2 * ux, y1: cy - lv / 2 * uy,
             y2: cy + lv / 2 * uy, g: 9.81, l: lv}
        # Midpoint velocity along the rod, relative velocity perpendicular to it.
        s, w = rng.normal(), rng.normal()
        vm = (s * ux, s * uy)
        vr = (-w * uy, w * ux)  # d/dt (P2 - P1) / 2
        p[x1d], p[y1d] = vm[0] - vr[0], vm[1] - vr[1]
        p[x2d], p[y2d] = vm[0] + vr[0], vm[1] + vr[1]
        return p

    return system, point


def drifting_particle():
    """Affine example: a particle in the plane with y_dot = Omega x (h = -Omega x)."""
    x, y = sp.symbols("x y")
    xd, yd = sp.symbols("x_dot y_dot")
    Om = sp.Symbol("Omega")
    L = (xd**2 + yd**2) / 2
    system = nhham.System(["x", "y"], L, [yd - Om * x], parameters={"Omega": 0.8},
                          name="drifting particle")

    def point(rng):
        p = {x: rng.normal(), y: rng.normal(), xd: rng.normal(), Om: 0.8}
        p[yd] = 0.8 * p[x]
        return p

    return system, point


def pendulum():
    """Pendulum in Cartesian coordinates: x^2 + y^2 = l^2, gravity along -y."""
    x, y = sp.symbols("x y")
    xd, yd = sp.symbols("x_dot y_dot")
    m, g, l = sp.symbols("m g l")
    return nhham.System(["x", "y"], m * (xd**2 + yd**2) / 2 - m * g * y,
                        holonomic=[x**2 + y**2 - l**2],
                        parameters={"m": 1.2, "g": 9.81, "l": 0.8})


IDENTITY_SYSTEMS = {
    "rolling disk": rolling_disk,
    "knife edge": knife_edge_inclined,
    "Chaplygin sleigh": chaplygin_sleigh,
    "two-particle rod": two_particle_rod,
}


def evaluate(expr, point):
    """Float value of a sympy expression at a point (dict symbol -> float)."""
    return float(sp.sympify(expr).xreplace({k: sp.Float(v, 30) for k, v in point.items()}).evalf(20))


def evaluate_matrix(matrix, point):
    sub = {k: sp.Float(v, 30) for k, v in point.items()}
    return np.array(matrix.xreplace(sub).evalf(20), dtype=float)
