"""Write the scene of a ball rolling inside a vertical cylinder, built with
sympy.physics.mechanics.

Usage::

    python examples/make_ball_in_cylinder.py [PATH]

writes ``examples/ball_in_cylinder.toml`` (or PATH; ``-`` for stdout).

A uniform ball (mass m, radius r, central inertia k m r^2 about every axis; k = 2/5 for a
solid ball) rolls without slipping on the inside of a fixed vertical circular cylinder of
radius R > r, under gravity g along -z. Coordinates: the centre's azimuth phi and height z
(the centre stays at distance R - r from the axis), and the ball's orientation by
body-fixed z-x-y angles (yaw, pitch, roll) of the body frame B, as in
``make_chaplygin_sphere.py``. L = T - V from ``Lagrangian(N, ball)`` with V = m g z; the
rolling constraints say that the material point at the contact, centre + omega x (r e_r),
has zero velocity: its tangential (e_phi) and vertical components (two affine
constraints; the radial one vanishes identically).
"""

from __future__ import annotations

import sys
from pathlib import Path

import sympy as sp
from sympy.physics import mechanics as me

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from scene_output import write_example  # noqa: E402
from nhham.system.mechanics import from_mechanics  # noqa: E402

VALUES = {"m": 0.05, "r": 0.02, "R": 0.1, "g": 9.81, "k": 0.4}


def build(values=None):
    """The nhham System of the ball in the cylinder (parameters m, r, R, g, k)."""
    yaw, pitch, roll, phi, z = me.dynamicsymbols("yaw pitch roll phi z")
    m, r, R, g, k = sp.symbols("m r R g k")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [phi, N.z])          # A.x = e_r, A.y = e_phi
    B = N.orientnew("B", "Body", [yaw, pitch, roll], "ZXY")
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", (R - r) * A.x + z * N.z)
    C.set_vel(N, C.pos_from(O).dt(N))
    ball = me.RigidBody("ball", C, B, m, (k * m * r**2 * me.inertia(B, 1, 1, 1), C))
    ball.potential_energy = m * g * z
    L = sp.trigsimp(me.Lagrangian(N, ball))
    contact = C.vel(N) + B.ang_vel_in(N).cross(r * A.x)
    nonhol = [sp.simplify(contact.dot(A.y)), sp.simplify(contact.dot(N.z))]
    return from_mechanics(L, [yaw, pitch, roll, phi, z], nonhol_coneqs=nonhol,
                          parameters=dict(values or VALUES), name="ball in a cylinder")


HEADER = """\
# A ball rolling inside a vertical cylinder (written by examples/make_ball_in_cylinder.py
# from a sympy.physics.mechanics model): a uniform ball (mass m, radius r, central inertia
# k m r^2 about every axis, k = 2/5 for a solid ball) rolls without slipping on the inside
# of a fixed vertical cylinder of radius R > r, gravity g along -z. phi, z: the centre, at
# ((R - r) cos phi, (R - r) sin phi, z); yaw, pitch, roll: body-fixed z-x-y angles (singular
# at pitch = +-pi/2: the [initial] motion keeps |pitch| < 0.91 up to t_end; at phi' = 5 it
# passes within 5e-4 of pi/2). n = 5, m = 2: the material point at the contact,
# C + r e_r, has zero velocity (its e_phi and z components; the e_r one vanishes).
#
# What `nhham classify` reports: C regular on M_1 (rank 2, exact), one stage, determined, no
#   free multipliers; not integrable (truly nonholonomic); on T*Q the two constraints are
#   second class (0 first class, 2 second class). ~1 s.
# By hand (Newton-Euler with the contact force F at C + r e_r; e_r, e_phi, e_z turn with
#   the centre: e_r' = phi' e_phi, e_phi' = -phi' e_r; omega = w_r e_r + w_phi e_phi + w_z e_z):
#   rolling: (R - r) phi' + r w_z = 0 and z' = r w_phi;
#   Newton: m (R - r) phi'' = F_phi, m z'' = F_z - m g (F_r = -m (R - r) phi'^2);
#   Euler, I = k m r^2, torque r e_r x F = r (F_phi e_z - F_z e_phi):
#     I (w_r' - phi' w_phi) = 0,  I (w_phi' + phi' w_r) = -r F_z,  I w_z' = r F_phi.
#   e_z: with w_z' = -(R - r) phi''/r, (1 + k) m (R - r) phi'' = 0: phi' = Omega is constant
#     (so is the spin about the vertical, w_z = -(R - r) Omega/r).
#   e_r: w_r' = Omega z'/r, so w_r = w_r0 + Omega (z - z0)/r (the spin about the radial axis
#     follows the height).
#   e_phi: with F_z = m (z'' + g), w_phi' = z''/r: (1 + k) z'' = -g - k r Omega w_r, i.e.
#     z'' = -omega^2 (z - z_c),  omega = sqrt(k/(1 + k)) |phi'|  (sqrt(2/7) |phi'| for the
#     solid ball: phi' the rate at which the centre and the contact point go round the axis;
#     = sqrt(k/(1 + k)) r |w_z|/(R - r) in the spin about the vertical; independent of g, m
#     and the amplitude), z_c = z0 - g/((1 + k) omega^2) - r w_r0/Omega
#     = z0 - g/(k Omega^2) - r w_r0/Omega;
#     z(t) = z_c + (z0 - z_c) cos(omega t) + (z0'/omega) sin(omega t).
#   [initial]: z0 = 0, z0' = 0, Omega = 20, w_r0 = w_phi0 = 0 (spin about the vertical only,
#     yaw_dot = -(R - r) Omega/r = -80): z(t) = z_c (1 - cos(omega t)), omega = 20 sqrt(2/7)
#     = 10.69044967649698 rad/s; the mean height is z_c = -g/(k Omega^2) = -g/((1 + k) omega^2)
#     = -0.0613125: the centre sinks on average, dips to 2 z_c and comes back up to z0.
# `nhham simulate` at rtol 1e-12, atol 1e-14: z(t) agrees with the closed form to 2e-10 over
#   10 s, phi' stays 20 to 2e-12. Energy is conserved (L = T - m g z, linear constraints).
"""


def initial_state(values=None, phi_dot: float = 20.0) -> dict:
    """Going round at the rate phi_dot at zero height, no vertical velocity: the spin
    about the vertical is omega_z = -(R - r) phi_dot / r (rolling), the others are 0."""
    v = dict(values or VALUES)
    return {"phi": 0.0, "z": 0.0, "yaw": 0.0, "pitch": 0.0, "roll": 0.0,
            "phi_dot": phi_dot, "z_dot": 0.0,
            "yaw_dot": -(v["R"] - v["r"]) * phi_dot / v["r"], "pitch_dot": 0.0,
            "roll_dot": 0.0}


def main(argv):
    write_example(argv, "ball_in_cylinder.toml", HEADER, build(), initial=initial_state())


if __name__ == "__main__":
    main(sys.argv)
