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


def blowup_system():
    """x'' = x^2 (V = -x^3/3) blows up in finite time; one trivial constraint."""
    return nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2 + x**3/3", ["y_dot"],
                        name="blow-up")


IDENTITY_SYSTEMS = {
    "rolling disk": rolling_disk,
    "knife edge": knife_edge_inclined,
    "Chaplygin sleigh": chaplygin_sleigh,
    "two-particle rod": two_particle_rod,
}


def evaluate(expr, point):
    """Float value of a sympy expression at a point (dict symbol -> float)."""
    return float(sp.sympify(expr).xreplace({k: sp.Float(v, 30) for k, v in point.items()}).evalf(20))


def zero(expr):
    """The expression simplifies to 0."""
    return sp.simplify(sp.sympify(expr)) == 0


def same_vector(a, b):
    """Two vectors of expressions are equal entry by entry (after simplification)."""
    a, b = sp.Matrix(a), sp.Matrix(b)
    return a.shape == b.shape and all(zero(x - y) for x, y in zip(a, b))


def evaluate_matrix(matrix, point):
    sub = {k: sp.Float(v, 30) for k, v in point.items()}
    return np.array(matrix.xreplace(sub).evalf(20), dtype=float)


# ======================================= singular C with a non-constant W (by hand)
# A point transformation q = f(Q) of a system solved by hand: L and the constraints are
# pulled back, W(Q) = J^T W_0 J is neither constant nor diagonal, and status, stage
# count, ranks and the multipliers are those of the original system.
q1, q2, q3, q4 = sp.symbols("q1 q2 q3 q4")
v1, v2, v3, v4 = sp.symbols("q1_dot q2_dot q3_dot q4_dot")
LOR = (v1**2 + v2**2 - v3**2) / 2  # the paper's Lorentzian kinetic energy


def pulled_back(coords, L, constraints, transform, name, holonomic=()):
    """The system in coordinates Q with q = transform[q] (the other q unchanged)."""
    Q = sp.symbols(coords)
    V = [sp.Symbol(f"{c}_dot") for c in coords]
    sub = {q: transform.get(q, q) for q in Q}
    vel = {v: sum((sp.diff(sub[q], p) * w for p, w in zip(Q, V)), sp.S.Zero)
           for q, v in zip(Q, V)}
    back = {**sub, **vel}
    return nhham.System(list(coords), sp.expand(L.xreplace(back)),
                        [sp.expand(c.xreplace(back)) for c in constraints],
                        holonomic=[h.xreplace(sub) for h in holonomic], name=name)


def curvilinear_3_2():
    """Example 3.2 (L = LOR + q1^2/2, phi = v1 + v3) with q3 -> q3 + sin(q2) and
    q2 -> q2 + q2^3/3.  W(q) is not constant, not diagonal, and
    det W = -(1 + q2^2)^2.  Known: phi -> q1 -> v1, ranks 0, 0, 1, lambda = q1."""
    return pulled_back(["q1", "q2", "q3"], LOR + q1**2 / 2, [v1 + v3],
                       {q3: q3 + sp.sin(q2), q2: q2 + q2**3 / 3}, "curvilinear 3.2")


def curvilinear_five_stage():
    """The five-stage walk-through (L = LOR + q1 q2, phi = v2 + v3) with q3 -> q3 + q1^2/2
    and q1 -> q1 + q1^3/3: secondary q1, v1, q2, v2 (up to factors), ranks 0, 0, 0, 0, 1."""
    return pulled_back(["q1", "q2", "q3"], LOR + q1 * q2, [v2 + v3],
                       {q3: q3 + q1**2 / 2, q1: q1 + q1**3 / 3}, "curvilinear five stages")


def curvilinear_free_multiplier():
    """The free-multiplier case (L = LOR + v4^2/2 - q4, phi1 = v2 + v3, phi2 = v4) with
    q3 -> q3 + cos(q4), q4 -> q4 + q4^3/3: underdetermined, lambda_1 free, rank C = 1."""
    return pulled_back(["q1", "q2", "q3", "q4"], LOR + v4**2 / 2 - q4, [v2 + v3, v4],
                       {q3: q3 + sp.cos(q4), q4: q4 + q4**3 / 3}, "curvilinear free")


def curvilinear_inconsistent():
    """The inconsistent case (L = LOR + q1 q2, phi1 = v1 + v3, phi2 = v2 - 1) with
    q3 -> q3 + q2^2, q1 -> q1 + q1^3: psi = q2 at stage 1, then 0 = 1 on M_2."""
    return pulled_back(["q1", "q2", "q3"], LOR + q1 * q2, [v1 + v3, v2 - 1],
                       {q3: q3 + q2**2, q1: q1 + q1**3}, "curvilinear inconsistent")


def sphere_with_knife():
    """Particle on the sphere r = l with the nonholonomic constraint z_dot = y x_dot."""
    x, y, z = sp.symbols("x y z")
    xd, yd, zd = sp.symbols("x_dot y_dot z_dot")
    m, l = sp.symbols("m l")
    return nhham.System(["x", "y", "z"], m * (xd**2 + yd**2 + zd**2) / 2, [zd - y * xd],
                        holonomic=[(x**2 + y**2 + z**2 - l**2) / 2],
                        parameters={"m": 1.3, "l": 1.1})


#: A Chaplygin sleigh (blade behind) as scene text, with a parameter u: a forward speed
#: for the [steady] tables the tests add.
SLEIGH_SCENE = """
name = "sleigh"
coordinates = ["x", "y", "theta"]
parameters = { m = 1.0, I = 0.25, a = 0.5, u = 2.0 }
lagrangian = "m*(x_dot**2 + y_dot**2)/2 + I*theta_dot**2/2"
constraints = ["-sin(theta)*x_dot + cos(theta)*y_dot - a*theta_dot"]
"""


def sleigh_with_values():
    """The Chaplygin sleigh (blade behind: -a theta_dot) with parameter values."""
    th = sp.Symbol("theta")
    xd, yd, thd = sp.symbols("x_dot y_dot theta_dot")
    m, I, a = sp.symbols("m I a")
    return nhham.System(["x", "y", "theta"], m * (xd**2 + yd**2) / 2 + I * thd**2 / 2,
                        [-sp.sin(th) * xd + sp.cos(th) * yd - a * thd],
                        parameters={"m": 1.5, "I": 0.4, "a": 0.6})


def example_3_2():
    """The paper's Example 3.2: L = LOR + q1^2/2, phi = v1 + v3 (phi -> q1 -> v1,
    lambda = q1)."""
    return nhham.System(["q1", "q2", "q3"], LOR + q1**2 / 2, [v1 + v3], name="Example 3.2")


def two_blocks():
    """Rolling disk (x, y, theta, phi) + Example 3.2 (q1, q2, q3), L the sum."""
    disk, _ = rolling_disk()
    return nhham.System(list(disk.coordinates) + [q1, q2, q3],
                        disk.lagrangian + LOR + q1**2 / 2, list(disk.constraints) + [v1 + v3],
                        parameters=dict(disk.parameter_values))


# ========================================================= the rolling disk as scene text
# A scene file's text in three pieces: the system, its [initial] table (on M_1:
# x_dot = R cos(theta) phi_dot = 2, y_dot = R sin(theta) phi_dot = 0) and [simulate].
DISK_SCENE = """\
name = "vertical rolling disk"
description = "a disk rolling upright without slipping"
coordinates = ["x", "y", "theta", "phi"]
parameters = { m = 1.0, I1 = 0.5, I2 = 0.25, R = 1.0 }
lagrangian = "m*(x_dot**2 + y_dot**2)/2 + I1*theta_dot**2/2 + I2*phi_dot**2/2"
constraints = ["x_dot - R*cos(theta)*phi_dot", "y_dot - R*sin(theta)*phi_dot"]
holonomic = []
"""
DISK_INITIAL = """
[initial]
x = 0.0
y = 0.0
theta = 0.0
phi = 0.0
x_dot = 2.0
y_dot = 0.0
theta_dot = 1.0
phi_dot = 2.0
"""
DISK_SIMULATE = """
[simulate]
t_end = 10.0
method = "DOP853"
rtol = 1e-10
"""


def same(a, b) -> bool:
    """Equal expressions: structurally, or their difference simplifies to 0."""
    return a == b or sp.simplify(a - b) == 0
