"""Write the scene of the rolling disc in 3-D, built with sympy.physics.mechanics.

Usage::

    python examples/make_rolling_disc_3d.py [PATH]

writes ``examples/rolling_disc_3d.toml`` (or PATH; ``-`` for stdout).

The model is the one of sympy's ``sympy/physics/mechanics/tests/test_kane5.py``
(a thin uniform disc, inertia m r^2/4 (1, 2, 1), rolling without slipping on a
horizontal plane; yaw q1, lean q2, spin q3 in body-fixed z-x-y angles, contact
point q4, q5), given as sympy users write it for ``KanesMethod``: body-fixed
generalized speeds u1..u3 (disc angular velocity components) and contact
velocities u4, u5, kinematic differential equations between q' and u, and the
rolling constraints in u. :func:`nhham.from_mechanics` solves the kinematic
equations for u and builds L = T - V in (q, q'). Names in the scene: yaw,
lean, spin, x, y.
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

VALUES = {"g": 9.81, "r": 0.26, "m": 3.43}   # test_kane5.py's numbers


def kane_model():
    """The test_kane5 construction: frame, q, u, kdes, rolling constraints, body, loads."""
    t = me.dynamicsymbols._t
    q1, q2, q3, q4, q5, u1, u2, u3, u4, u5 = me.dynamicsymbols("yaw lean spin x y u1:6")
    g, r, m = sp.symbols("g r m")
    ground = me.RigidBody("ground")
    disc = me.RigidBody("disk", mass=m)
    disc.inertia = (m * r ** 2 / 4 * me.inertia(disc.frame, 1, 2, 1), disc.masscenter)
    ground.masscenter.set_vel(ground.frame, 0)
    disc.masscenter.set_vel(disc.frame, 0)
    int_frame = me.ReferenceFrame("int_frame")
    int_frame.orient_body_fixed(ground.frame, (q1, q2, 0), "zxy")
    disc.frame.orient_axis(int_frame, int_frame.y, q3)
    g_w_d = disc.frame.ang_vel_in(ground.frame)
    disc.frame.set_ang_vel(ground.frame, u1 * disc.x + u2 * disc.y + u3 * disc.z)
    cp = ground.masscenter.locatenew("contact_point", q4 * ground.x + q5 * ground.y)
    cp.set_vel(ground.frame, u4 * ground.x + u5 * ground.y)
    disc.masscenter.set_pos(cp, r * int_frame.z)
    disc.masscenter.set_vel(ground.frame, me.cross(disc.frame.ang_vel_in(ground.frame),
                                                   disc.masscenter.pos_from(cp)))
    kdes = [g_w_d.dot(disc.x) - u1, g_w_d.dot(disc.y) - u2, g_w_d.dot(disc.z) - u3,
            q4.diff(t) - u4, q5.diff(t) - u5]
    v0 = cp.vel(ground.frame) + me.cross(disc.frame.ang_vel_in(int_frame),
                                         cp.pos_from(disc.masscenter))
    fnh = [v0.dot(ground.x), v0.dot(ground.y)]
    return dict(frame=ground.frame, origin=ground.masscenter, q=[q1, q2, q3, q4, q5],
                u=[u1, u2, u3, u4, u5], kdes=kdes, fnh=fnh, bodies=[disc],
                loads=[(disc.masscenter, -disc.mass * g * ground.z)])


def build(values=None):
    """The nhham System of the disc (parameters g, r, m with values)."""
    k = kane_model()
    return from_mechanics(q=k["q"], bodies=k["bodies"], loads=k["loads"], frame=k["frame"],
                          origin=k["origin"], u=k["u"], kd_eqs=k["kdes"],
                          velocity_constraints=k["fnh"],
                          parameters=dict(values or VALUES), name="rolling disc (3-D)")


#: Upright rolling straight ahead with spin rate w (a parameter): the contact
#: point moves along -r w in the heading direction (yaw = 0: the x axis).
STEADY = {"yaw": "0", "lean": "0", "spin": "0", "x": "0", "y": "0",
          "yaw_dot": "0", "lean_dot": "0", "spin_dot": "w", "x_dot": "r*w", "y_dot": "0"}

HEADER = """\
# The rolling disc in 3-D (written by examples/make_rolling_disc_3d.py from the
# sympy.physics.mechanics model of sympy's test_kane5.py: thin uniform disc, body-fixed
# speeds, rolling constraints in u). yaw, lean, spin: z-x-y body-fixed angles; x, y: contact.
# n = 5, m = 2 (no slip at the contact, two affine constraints).
#
# What `nhham classify` reports: C regular on M_1 (rank 2, exact), one stage, determined, no
#   free multipliers, not integrable; on T*Q 2 first class, 0 second class (~3 s).
# What `nhham linearize` finds about the [steady] upright rolling at spin rate w: neutral
#   yaw, spin, x, y and spin_dot; in (lean, yaw_dot, lean_dot) eigenvalues 0 and a pair with
#   lambda^2 = -(I3 (I3 + m r^2) w^2 - m g r I1) / (I1 (I1 + m r^2)), I1 = m r^2/4, I3 = m r^2/2:
#   spectrally stable iff w^2 > g / (3 r) (textbook condition: upright rolling is stable
#   above the speed sqrt(g r / 3); e.g. Neimark & Fufaev, Dynamics of Nonholonomic Systems,
#   ch. 3; tests/system/test_mechanics_models.py). The 0 is the neighbouring steady circles.
"""


def main(argv):
    values = dict(VALUES, w=6.0)
    initial = {"yaw": 0.0, "lean": 0.0, "spin": 0.0, "x": 0.0, "y": 0.0, "yaw_dot": 0.0,
               "lean_dot": 0.2, "spin_dot": 6.0, "x_dot": values["r"] * 6.0, "y_dot": 0.0}
    write_example(argv, "rolling_disc_3d.toml", HEADER, build(values), initial=initial,
                  steady=STEADY)


if __name__ == "__main__":
    main(sys.argv)
