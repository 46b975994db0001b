"""Ready-made mechanical systems with nonholonomic and holonomic constraints.

Every constructor returns a validated :class:`nhham.System` whose parameters
carry default numeric values. Keyword arguments override the values;
``symbolic=True`` leaves every parameter without a value (a purely symbolic
system: numbers are then needed only when something numeric is asked for).

Velocities follow the library convention: coordinate ``x`` has velocity
``x_dot``. Docstrings write q' for the velocity of q.

:data:`MODELS` maps a short name to each constructor; every constructor can
be called without arguments.
"""

from __future__ import annotations

from typing import Callable, Mapping

import sympy as sp

from nhham.errors import InputError
from nhham.system.expressions import parse_expression
from nhham.system.naming import velocity_symbol
from nhham.system.description import System

__all__ = [
    "rolling_disk",
    "knife_edge_inclined",
    "chaplygin_sleigh",
    "nonholonomic_particle",
    "rolling_ball",
    "ball_on_turntable",
    "snakeboard",
    "pendulum_cartesian",
    "particle_on_sphere",
    "two_particle_rod",
    "paper_example_3_1",
    "paper_example_3_2",
    "snake",
    "snake_centres",
    "snake_chain_lagrangian",
    "MODELS",
]

_HALF = sp.Rational(1, 2)


# ----------------------------------------------------------------- helpers
def _coords(names: str):
    """Coordinate symbols and their velocity symbols for space-separated names."""
    qs = sp.symbols(names, seq=True)
    return qs, tuple(velocity_symbol(q) for q in qs)


def _parameters(values: Mapping[str, float], symbolic: bool):
    """The ``parameters`` argument of :class:`System` for these defaults.

    Returns the symbols (in the order given) and the mapping or name list.
    """
    syms = tuple(sp.Symbol(name) for name in values)
    if symbolic:
        return syms, [s.name for s in syms]
    return syms, {name: float(value) for name, value in values.items()}


def _quadratic_form(W, vels):
    """1/2 v^T W v written out term by term (each pair once)."""
    n = len(vels)
    terms = [_HALF * W[a][a] * vels[a] ** 2 for a in range(n) if W[a][a] != 0]
    terms += [W[a][b] * vels[a] * vels[b]
              for a in range(n) for b in range(a + 1, n) if W[a][b] != 0]
    return sp.Add(*terms)


# ------------------------------------------------------------------ models
def rolling_disk(*, m=1.0, I1=0.25, I2=0.5, R=1.0, symbolic=False) -> System:
    """Vertical disk rolling without slipping on a horizontal plane (paper Ex. 2.1).

    Coordinates ``x, y`` (centre of mass, equal to the contact point's
    position in the plane), ``theta`` (heading: angle between the disk's
    plane and the x axis) and ``phi`` (rolling angle about the axle).

    Lagrangian::

        L = m (x'^2 + y'^2)/2 + I1 theta'^2/2 + I2 phi'^2/2

    Constraints (rolling without slipping; linear)::

        x' - R cos(theta) phi' = 0,   y' - R sin(theta) phi' = 0

    Physics: the heading rate theta' and the rolling rate phi' are constant;
    the centre moves on a circle of radius R |phi'/theta'| (a straight line
    if theta' = 0). C = -mu W^-1 mu^T is regular everywhere:
    C = -(1/m) Id - (R^2/I2) (cos, sin)^T (cos, sin). A uniform disk has
    I1 = m R^2/4 (about a diameter) and I2 = m R^2/2 (about the axle), the
    defaults with m = R = 1.

    Parameters
    ----------
    m, I1, I2, R : float
        Mass, moment of inertia about the vertical diameter, about the axle,
        and radius.
    symbolic : bool
        If True, the parameters get no numeric values.
    """
    (x, y, th, ph), (xd, yd, thd, phd) = _coords("x y theta phi")
    (m_, I1_, I2_, R_), params = _parameters(dict(m=m, I1=I1, I2=I2, R=R), symbolic)
    L = m_ * (xd**2 + yd**2) / 2 + I1_ * thd**2 / 2 + I2_ * phd**2 / 2
    cons = [xd - R_ * sp.cos(th) * phd, yd - R_ * sp.sin(th) * phd]
    return System([x, y, th, ph], L, cons, parameters=params, name="vertical rolling disk")


def knife_edge_inclined(*, m=1.0, I=0.1, g=9.81, alpha=0.3, symbolic=False) -> System:
    """Knife edge (skate) sliding on an inclined plane.

    Coordinates ``x, y`` (contact point in the plane; x points down the
    slope) and ``phi`` (angle of the blade with the x axis).

    Lagrangian (gravity component g sin(alpha) along the slope)::

        L = m (x'^2 + y'^2)/2 + I phi'^2/2 + m g sin(alpha) x

    Constraint (no velocity across the blade; linear)::

        sin(phi) x' - cos(phi) y' = 0

    Physics: phi' = w is constant and the speed u = cos(phi) x' + sin(phi) y'
    along the blade obeys u' = g sin(alpha) cos(phi). Starting from rest
    with phi(0) = 0 the skate moves on the cycloid-like curve
    x = g sin(alpha)/(2 w^2) sin^2(w t), y = g sin(alpha)/(2 w^2) (w t - sin(2 w t)/2)
    (Bloch, Nonholonomic Mechanics and Control, §1.6): it never slides
    down the slope on average.

    Parameters
    ----------
    m, I, g, alpha : float
        Mass, moment of inertia about the vertical axis through the contact
        point, gravitational acceleration, slope angle.
    symbolic : bool
        If True, the parameters get no numeric values.
    """
    (x, y, ph), (xd, yd, phd) = _coords("x y phi")
    (m_, I_, g_, a_), params = _parameters(dict(m=m, I=I, g=g, alpha=alpha), symbolic)
    L = m_ * (xd**2 + yd**2) / 2 + I_ * phd**2 / 2 + m_ * g_ * sp.sin(a_) * x
    cons = [sp.sin(ph) * xd - sp.cos(ph) * yd]
    return System([x, y, ph], L, cons, parameters=params, name="knife edge on an inclined plane")


def chaplygin_sleigh(*, m=1.0, I=0.25, a=0.5, symbolic=False) -> System:
    """Chaplygin sleigh: a rigid body on a plane supported by a knife edge.

    Coordinates ``x, y`` (centre of mass) and ``theta`` (heading). The blade
    touches the plane at distance ``a`` behind the centre of mass, at
    (x - a cos(theta), y - a sin(theta)), and is aligned with the heading.

    Lagrangian (I is the moment of inertia about the centre of mass)::

        L = m (x'^2 + y'^2)/2 + I theta'^2/2

    Constraint (the contact point does not move across the blade; linear)::

        -sin(theta) x' + cos(theta) y' - a theta' = 0

    Physics: with u = cos(theta) x' + sin(theta) y' (forward speed of the
    centre of mass) and w = theta', the reduced equations are
    u' = a w^2, w' = -m a u w / (I + m a^2): w decays to zero and u grows
    to a limit; energy is conserved. (Writing x, y for the contact point
    instead gives the equivalent form found in Bloch's book.)

    Parameters
    ----------
    m, I, a : float
        Mass, inertia about the centre of mass, distance from the centre of
        mass to the contact point.
    symbolic : bool
        If True, the parameters get no numeric values.
    """
    (x, y, th), (xd, yd, thd) = _coords("x y theta")
    (m_, I_, a_), params = _parameters(dict(m=m, I=I, a=a), symbolic)
    L = m_ * (xd**2 + yd**2) / 2 + I_ * thd**2 / 2
    cons = [-sp.sin(th) * xd + sp.cos(th) * yd - a_ * thd]
    return System([x, y, th], L, cons, parameters=params, name="Chaplygin sleigh")


def nonholonomic_particle(*, m=1.0, potential=None, potential_parameters=None,
                          symbolic=False) -> System:
    """The nonholonomic particle (Rosenberg; Bloch §1.4): a point in R^3 with z' = y x'.

    Coordinates ``x, y, z``.

    Lagrangian::

        L = m (x'^2 + y'^2 + z'^2)/2 - V(x, y, z)

    Constraint (linear, non-integrable: the Heisenberg distribution)::

        z' - y x' = 0

    Physics: without a potential, y' is constant and so is
    x' sqrt(1 + y^2) (energy m (x'^2 (1 + y^2) + y'^2)/2 on M_1); the
    multiplier is lambda = -m x' y'/(1 + y^2).

    Parameters
    ----------
    m : float
        Mass.
    potential : str or sympy.Expr, optional
        V in the coordinates ``x, y, z`` and the names of
        ``potential_parameters``; strings are parsed safely (never evaluated).
        Default: no potential.
    potential_parameters : mapping of str to float, optional
        Extra parameters used by the potential, with default values
        (``{"k": 1.0}`` for ``"k*(x**2 + y**2)/2"``).
    symbolic : bool
        If True, the parameters get no numeric values.

    Raises
    ------
    InputError
        If the potential uses velocities or unknown names.
    """
    (x, y, z), (xd, yd, zd) = _coords("x y z")
    values = dict(m=m) | dict(potential_parameters or {})
    syms, params = _parameters(values, symbolic)
    table = {s.name: s for s in (x, y, z) + syms}
    V = _potential(potential, table)
    L = syms[0] * (xd**2 + yd**2 + zd**2) / 2 - V
    return System([x, y, z], L, [zd - y * xd], parameters=params, name="nonholonomic particle")


def _potential(potential, table):
    """The potential as a sympy expression in the names of ``table``."""
    if potential is None:
        return sp.S.Zero
    if isinstance(potential, str):
        return parse_expression(potential, table, where="potential")
    expr = sp.sympify(potential)
    unknown = sorted(s.name for s in expr.free_symbols if s.name not in table)
    if unknown:
        raise InputError(f"potential: unknown name(s) {', '.join(unknown)} in {expr} "
                         f"(known: {', '.join(sorted(table))}; declare extra names in "
                         f"potential_parameters)")
    return expr.xreplace({s: table[s.name] for s in expr.free_symbols})


def _ball_angular_velocity(phi, theta, psi, phid, thetad, psid):
    """Space-frame angular velocity for z-x-z Euler angles R = Rz(phi) Rx(theta) Rz(psi)."""
    return (
        thetad * sp.cos(phi) + psid * sp.sin(theta) * sp.sin(phi),
        thetad * sp.sin(phi) - psid * sp.sin(theta) * sp.cos(phi),
        phid + psid * sp.cos(theta),
    )


def _ball(Omega, m, r, I, symbolic, name):
    """Ball on a plane turning with angular velocity Omega (Omega None: fixed plane)."""
    (x, y, ph, th, ps), (xd, yd, phd, thd, psd) = _coords("x y phi theta psi")
    values = dict(m=m, r=r, I=0.4 * m * r**2 if I is None else I)
    if Omega is not None:
        values["Omega"] = Omega
    syms, params = _parameters(values, symbolic)
    m_, r_, I_ = syms[:3]
    wx, wy, _ = _ball_angular_velocity(ph, th, ps, phd, thd, psd)
    # |omega|^2 written directly: the cross terms of wx^2 + wy^2 cancel.
    L = m_ * (xd**2 + yd**2) / 2 + I_ * (phd**2 + thd**2 + psd**2
                                         + 2 * sp.cos(th) * phd * psd) / 2
    # Contact point velocity v + omega x (-r e_z) = (x' - r wy, y' + r wx) must
    # equal the plane's velocity Omega e_z x (x, y) = (-Omega y, Omega x).
    cons = [xd - r_ * wy, yd + r_ * wx]
    if Omega is not None:
        Om = syms[3]
        cons = [cons[0] + Om * y, cons[1] - Om * x]
    return System([x, y, ph, th, ps], L, cons, parameters=params, name=name)


def rolling_ball(*, m=1.0, r=1.0, I=None, symbolic=False) -> System:
    """Homogeneous ball rolling without slipping on a fixed horizontal plane.

    Coordinates ``x, y`` (centre of the ball) and z-x-z Euler angles
    ``phi, theta, psi`` of the ball's attitude, R = Rz(phi) Rx(theta) Rz(psi).
    The angular velocity (space frame) is then affine in the angle rates::

        omega = (theta' cos(phi) + psi' sin(theta) sin(phi),
                 theta' sin(phi) - psi' sin(theta) cos(phi),
                 phi' + psi' cos(theta)),

    so rolling is a pair of linear constraints on TQ. (The angular velocity
    components themselves are quasi-velocities, not coordinate velocities.)
    The Euler angles are singular at theta = 0, pi, where W degenerates.

    Lagrangian (inertia I about every axis through the centre)::

        L = m (x'^2 + y'^2)/2 + I (phi'^2 + theta'^2 + psi'^2 + 2 cos(theta) phi' psi')/2

    Constraints (contact point at rest: v + omega x (-r e_z) = 0)::

        x' - r (theta' sin(phi) - psi' sin(theta) cos(phi)) = 0
        y' + r (theta' cos(phi) + psi' sin(theta) sin(phi)) = 0

    Physics: the centre moves on a straight line at constant speed and
    omega is constant.

    Parameters
    ----------
    m, r : float
        Mass and radius.
    I : float, optional
        Moment of inertia about a diameter; default 2 m r^2/5 (homogeneous).
    symbolic : bool
        If True, the parameters (m, r, I) get no numeric values.
    """
    return _ball(None, m, r, I, symbolic, "rolling ball")


def ball_on_turntable(Omega=1.0, *, m=1.0, r=1.0, I=None, symbolic=False) -> System:
    """Homogeneous ball rolling on a plane that turns with constant angular velocity.

    The plane rotates about the vertical z axis through the origin with
    angular velocity ``Omega``. Coordinates, Lagrangian and angular velocity
    as in :func:`rolling_ball` (inertial frame; x, y the centre).

    Constraints (contact point moves with the plane: affine, h != 0)::

        x' - r (theta' sin(phi) - psi' sin(theta) cos(phi)) + Omega y = 0
        y' + r (theta' cos(phi) + psi' sin(theta) sin(phi)) - Omega x = 0

    Physics: the centre's velocity obeys v' = (I/(I + m r^2)) Omega e_z x v,
    so the centre moves on a circle with angular frequency
    Omega I/(I + m r^2) = 2 Omega/7 for a homogeneous ball, whatever the
    initial data (a classical result; e.g. Neimark & Fufaev, Ch. III).

    Parameters
    ----------
    Omega : float
        Angular velocity of the turntable.
    m, r : float
        Mass and radius of the ball.
    I : float, optional
        Moment of inertia about a diameter; default 2 m r^2/5.
    symbolic : bool
        If True, the parameters (m, r, I, Omega) get no numeric values.
    """
    return _ball(Omega, m, r, I, symbolic, "ball on a turntable")


def snakeboard(*, m=1.0, J=1 / 3, J_r=0.2, J_w=0.05, r=1.0, symbolic=False) -> System:
    """The snakeboard (Ostrowski, Burdick, Lewis & Murray 1995).

    Coordinates ``x, y`` (centre of the board), ``theta`` (board heading),
    ``psi`` (rotor angle relative to the board) and ``phi`` (steering angle
    of the wheel axles: front axle at theta + phi, back axle at theta - phi).
    The axles sit at distance r ahead of and behind the centre.

    Lagrangian (board inertia J, rotor J_r, each axle J_w)::

        L = m (x'^2 + y'^2)/2 + J theta'^2/2 + J_r (theta' + psi')^2/2
            + J_w ((theta' + phi')^2 + (theta' - phi')^2)/2

    Constraints (no sideways slip of either axle; linear)::

        -sin(theta + phi) x' + cos(theta + phi) y' + r cos(phi) theta' = 0
        -sin(theta - phi) x' + cos(theta - phi) y' - r cos(phi) theta' = 0

    Physics: as phi -> pi/2 both one-forms tend to +/-(cos(theta) dx +
    sin(theta) dy): mu loses rank and C = -mu W^-1 mu^T becomes singular
    (det C ~ cos(phi)^2); for phi = pi/2 exactly the two constraints are
    dependent. Rotor and steering oscillations propel the board
    (gait generation).

    Parameters
    ----------
    m, J, J_r, J_w, r : float
        Mass, board inertia, rotor inertia, axle inertia, half wheel base.
    symbolic : bool
        If True, the parameters get no numeric values.
    """
    (x, y, th, ps, ph), (xd, yd, thd, psd, phd) = _coords("x y theta psi phi")
    (m_, J_, Jr_, Jw_, r_), params = _parameters(
        dict(m=m, J=J, J_r=J_r, J_w=J_w, r=r), symbolic)
    L = (m_ * (xd**2 + yd**2) / 2 + J_ * thd**2 / 2 + Jr_ * (thd + psd)**2 / 2
         + Jw_ * ((thd + phd)**2 + (thd - phd)**2) / 2)
    cons = [
        -sp.sin(th + ph) * xd + sp.cos(th + ph) * yd + r_ * sp.cos(ph) * thd,
        -sp.sin(th - ph) * xd + sp.cos(th - ph) * yd - r_ * sp.cos(ph) * thd,
    ]
    return System([x, y, th, ps, ph], L, cons, parameters=params, name="snakeboard")


def pendulum_cartesian(*, m=1.0, g=9.81, l=1.0, symbolic=False) -> System:
    """Planar pendulum in Cartesian coordinates (a holonomic constraint).

    Coordinates ``x, y`` of the bob (y up, pivot at the origin).

    Lagrangian::

        L = m (x'^2 + y'^2)/2 - m g y

    Holonomic constraint::

        x^2 + y^2 - l^2 = 0     (complete lift 2 x x' + 2 y y' = 0)

    Physics: the simple pendulum; with angle a from the downward vertical,
    a'' = -(g/l) sin(a). Constrained acceleration: (x'', y'') = -g e_y + k (x, y)
    with k = (g y - (x'^2 + y'^2))/l^2 on M_1.

    Parameters
    ----------
    m, g, l : float
        Mass, gravitational acceleration, length.
    symbolic : bool
        If True, the parameters get no numeric values.
    """
    (x, y), (xd, yd) = _coords("x y")
    (m_, g_, l_), params = _parameters(dict(m=m, g=g, l=l), symbolic)
    L = m_ * (xd**2 + yd**2) / 2 - m_ * g_ * y
    return System([x, y], L, holonomic=[x**2 + y**2 - l_**2], parameters=params,
                  name="pendulum (Cartesian)")


def particle_on_sphere(*, m=1.0, g=9.81, R=1.0, symbolic=False) -> System:
    """A particle on a sphere of radius R under gravity (spherical pendulum).

    Coordinates ``x, y, z`` (z up, sphere centred at the origin).

    Lagrangian::

        L = m (x'^2 + y'^2 + z'^2)/2 - m g z

    Holonomic constraint::

        x^2 + y^2 + z^2 - R^2 = 0

    Physics: the constrained acceleration on M_1 is
    -g e_z + k (x, y, z) with k = (g z - |v|^2)/R^2; the vertical angular
    momentum x y' - y x' and the energy are conserved. With g = 0 the
    particle moves on great circles at constant speed.

    Parameters
    ----------
    m, g, R : float
        Mass, gravitational acceleration, radius.
    symbolic : bool
        If True, the parameters get no numeric values.
    """
    (x, y, z), (xd, yd, zd) = _coords("x y z")
    (m_, g_, R_), params = _parameters(dict(m=m, g=g, R=R), symbolic)
    L = m_ * (xd**2 + yd**2 + zd**2) / 2 - m_ * g_ * z
    return System([x, y, z], L, holonomic=[x**2 + y**2 + z**2 - R_**2], parameters=params,
                  name="particle on a sphere")


def two_particle_rod(*, g=9.81, l=1.0, symbolic=False) -> System:
    """Two unit masses joined by a rigid massless rod in a vertical plane (paper Ex. 4.1).

    Coordinates in the paper's order ``x1, x2, y1, y2`` with P1 = (x1, y1)
    and P2 = (x2, y2), y up. (The paper's text says "(x1, x2) and (y1, y2)
    are the coordinates of P1 and P2", but its Lagrangian and constraints
    only make sense with P1 = (x1, y1), P2 = (x2, y2).) The midpoint of the
    rod may only move along the rod (Gantmacher's example: a knife edge at
    the midpoint).

    Lagrangian (m = 1 as in the paper)::

        L = (x1'^2 + x2'^2 + y1'^2 + y2'^2)/2 - g (y1 + y2)

    Holonomic constraint (rod length)::

        h1 = ((x2 - x1)^2 + (y2 - y1)^2 - l^2)/2

    Nonholonomic constraint (midpoint velocity parallel to the rod)::

        phi2 = (x2 - x1)(y2' + y1') - (x2' + x1')(y2 - y1)

    Physics: C = -2 ((x2-x1)^2 + (y2-y1)^2) Id = -2 l^2 Id on M_1; the
    multipliers are lambda1 = |v2 - v1|^2/(2 l^2) and
    lambda2 = (x2' y1' - x1' y2' - g (x2 - x1))/l^2 on M_1.

    Parameters
    ----------
    g, l : float
        Gravitational acceleration and rod length.
    symbolic : bool
        If True, the parameters get no numeric values.
    """
    (x1, x2, y1, y2), (x1d, x2d, y1d, y2d) = _coords("x1 x2 y1 y2")
    (g_, l_), params = _parameters(dict(g=g, l=l), symbolic)
    L = (x1d**2 + x2d**2 + y1d**2 + y2d**2) / 2 - g_ * (y1 + y2)
    X, Y = x2 - x1, y2 - y1
    h1 = (X**2 + Y**2 - l_**2) / 2
    phi2 = X * (y2d + y1d) - (x2d + x1d) * Y
    return System([x1, x2, y1, y2], L, [phi2], holonomic=[h1], parameters=params,
                  name="two particles joined by a rod (paper Example 4.1)")


def paper_example_3_1() -> System:
    """The paper's Example 3.1: an indefinite metric with a null constraint.

    Coordinates ``q1, q2, q3``.

    Lagrangian (Lorentzian kinetic energy)::

        L = (q1'^2 + q2'^2 - q3'^2)/2

    Constraint::

        q2' + q3' = 0

    Physics: Z = -d/dv2 + d/dv3 has Z(phi) = 0 and xi_L(phi) = 0
    identically: C = 0 on M_1, no new constraint appears, M_f = M_1 and the
    multiplier is free. The dynamics is the family xi_L + lambda Z (fully
    undetermined). The constraint is integrable (q2 + q3 = const).
    """
    (q1, q2, q3), (v1, v2, v3) = _coords("q1 q2 q3")
    L = (v1**2 + v2**2 - v3**2) / 2
    return System([q1, q2, q3], L, [v2 + v3], name="paper Example 3.1")


def paper_example_3_2() -> System:
    """The paper's Example 3.2: the constraint algorithm stops at M_3.

    Coordinates ``q1, q2, q3``.

    Lagrangian::

        L = (q1'^2 + q2'^2 - q3'^2)/2 + q1^2/2

    Constraint::

        q1' + q3' = 0

    Physics: Z(phi) = 0 and xi_L(phi) = q1 gives M_2 = {phi = 0, q1 = 0};
    then xi_L(q1) = q1' gives M_3 = {q1 = 0, q1' = 0, q3' = 0}, where
    Z(q1') = -1 fixes lambda = q1 (= 0 on M_3). The dynamics on M_3 is
    xi_L + q1 Z.
    """
    (q1, q2, q3), (v1, v2, v3) = _coords("q1 q2 q3")
    L = (v1**2 + v2**2 - v3**2) / 2 + q1**2 / 2
    return System([q1, q2, q3], L, [v1 + v3], name="paper Example 3.2")


# ------------------------------------------------------------------- snake
def _snake_link_weights(N):
    """k[i][j]: centre of link i is (x, y) + (l/2) sum_j k[i][j] e(theta_j).

    Link 1's centre is (x, y); from there each joint adds half a link on
    either side: c_{i+1} = c_i + (l/2)(e(theta_i) + e(theta_{i+1})).
    """
    k = [[0] * N for _ in range(N)]
    for i in range(1, N):
        k[i] = list(k[i - 1])
        k[i][i - 1] += 1
        k[i][i] += 1
    return k


def snake_chain_lagrangian(N: int):
    """The snake's L written as the sum of its links' kinetic energies, unexpanded.

    m |c_i'|^2 / 2 + m l^2 theta_i'^2 / 24 per link, as a sympy.physics.mechanics
    user writes it from the chain geometry; the same function as ``snake(N).lagrangian``.
    """
    base = snake(N, symbolic=True)
    q, v = base.coordinates, base.velocities
    m, l = sp.symbols("m l")
    L = sp.S.Zero
    for X, Y in snake_centres(N):
        dX = sum(X.diff(a) * w for a, w in zip(q, v))
        dY = sum(Y.diff(a) * w for a, w in zip(q, v))
        L += m * (dX**2 + dY**2) / 2
    return L + sum(m * l**2 / 24 * w**2 for w in v[2:])


def snake_centres(N: int, l=None):
    """Centres (X_i, Y_i) of the snake's links as expressions in x, y, theta1..thetaN.

    Used to check :func:`snake`'s kinetic energy (and handy for plotting).

    Parameters
    ----------
    N : int
        Number of links.
    l : sympy.Expr or float, optional
        Link length; default the symbol ``l``.

    Returns
    -------
    list of (sympy.Expr, sympy.Expr)
    """
    N = _check_links(N)
    l = sp.Symbol("l") if l is None else l
    x, y = sp.symbols("x y")
    th = sp.symbols(f"theta1:{N + 1}", seq=True)
    k = _snake_link_weights(N)
    return [(x + l / 2 * sum(k[i][j] * sp.cos(th[j]) for j in range(N)),
             y + l / 2 * sum(k[i][j] * sp.sin(th[j]) for j in range(N))) for i in range(N)]


def _check_links(N):
    if isinstance(N, bool) or not isinstance(N, int) or N < 1:
        raise InputError(f"snake: N must be a positive integer number of links, got {N!r}")
    return N


def snake(N: int = 3, *, m=1.0, l=1.0, symbolic=False) -> System:
    """The N-link nonholonomic snake: a planar chain with a knife edge on every link.

    N uniform links of mass m and length l (inertia m l^2/12 about the
    centre) are joined end to end by free pin joints. Each link carries a
    knife edge (a passive wheel pair) at its centre, so no link centre moves
    across its link. Coordinates (n = N + 2): ``x, y`` (centre of link 1)
    and the absolute link angles ``theta1 .. thetaN``. Centre of link i::

        c_i = (x, y) + (l/2) sum_j k_ij e(theta_j),   e(t) = (cos t, sin t),

    with k_ij = 1 for j = 1 and j = i, 2 for 1 < j < i, 0 for j > i
    (and c_1 = (x, y)).

    Lagrangian (total kinetic energy, sum_i m |c_i'|^2/2 + m l^2 theta_i'^2/24)
    written as v^T W v / 2 with::

        W_xx = W_yy = N m,          W_xy = 0,
        W_x,j = -(m l/2) K_j sin(theta_j),  W_y,j = (m l/2) K_j cos(theta_j),
        W_j,k = (m l^2/4) S_jk cos(theta_j - theta_k) + delta_jk m l^2/12,

    where K_j = sum_i k_ij and S_jk = sum_i k_ij k_ik.

    Constraints (m = N; linear)::

        -sin(theta_i) x' + cos(theta_i) y' + (l/2) sum_j k_ij cos(theta_i - theta_j) theta_j' = 0

    Physics: a passive snake (no joint torques): energy is conserved and
    the constraints are non-integrable; C is negative definite (W positive
    definite, mu of full rank). snake(1) is the free knife edge (skate).

    Parameters
    ----------
    N : int
        Number of links (>= 1).
    m, l : float
        Mass and length of each link.
    symbolic : bool
        If True, the parameters get no numeric values.

    Raises
    ------
    InputError
        If N is not a positive integer.
    """
    N = _check_links(N)
    (m_, l_), params = _parameters(dict(m=m, l=l), symbolic)
    x, y = sp.symbols("x y")
    th = sp.symbols(f"theta1:{N + 1}", seq=True)
    q = (x, y) + tuple(th)
    v = tuple(velocity_symbol(s) for s in q)
    k = _snake_link_weights(N)
    W = _snake_hessian(N, k, th, m_, l_)
    L = _quadratic_form(W, v)
    cons = []
    for i in range(N):
        along = sp.Add(*[k[i][j] * sp.cos(th[i] - th[j]) * v[2 + j]
                         for j in range(N) if k[i][j]])
        cons.append(-sp.sin(th[i]) * v[0] + sp.cos(th[i]) * v[1] + l_ / 2 * along)
    return System(q, L, cons, parameters=params, name=f"{N}-link nonholonomic snake")


def _snake_hessian(N, k, th, m, l):
    """The snake's kinetic-energy matrix W (list of lists), from the link weights."""
    n = N + 2
    W = [[sp.S.Zero] * n for _ in range(n)]
    W[0][0] = W[1][1] = N * m
    for j in range(N):
        K = sum(k[i][j] for i in range(N))
        W[0][2 + j] = W[2 + j][0] = -m * l / 2 * K * sp.sin(th[j])
        W[1][2 + j] = W[2 + j][1] = m * l / 2 * K * sp.cos(th[j])
        for jj in range(j, N):
            S = sum(k[i][j] * k[i][jj] for i in range(N))
            entry = m * l**2 / 4 * S * sp.cos(th[j] - th[jj])
            if j == jj:
                entry += m * l**2 / 12
            W[2 + j][2 + jj] = W[2 + jj][2 + j] = entry
    return W


#: Short name -> constructor; every constructor runs without arguments.
MODELS: Mapping[str, Callable[..., System]] = {
    "rolling_disk": rolling_disk,
    "knife_edge_inclined": knife_edge_inclined,
    "chaplygin_sleigh": chaplygin_sleigh,
    "nonholonomic_particle": nonholonomic_particle,
    "rolling_ball": rolling_ball,
    "ball_on_turntable": ball_on_turntable,
    "snakeboard": snakeboard,
    "pendulum_cartesian": pendulum_cartesian,
    "particle_on_sphere": particle_on_sphere,
    "two_particle_rod": two_particle_rod,
    "paper_example_3_1": paper_example_3_1,
    "paper_example_3_2": paper_example_3_2,
    "snake": snake,
}
