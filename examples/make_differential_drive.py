"""Write the scene of a differential-drive robot with a caster, built with sympy.physics.mechanics.

Usage::

    python examples/make_differential_drive.py [PATH]

writes ``examples/differential_drive.toml`` (or PATH; ``-`` for stdout).

A chassis (mass mc, inertia Ic about its centre of mass G) on two coaxial
wheels (mass mw, spin inertia Iw, turn inertia Id, radius r) at +-b from the
axle midpoint A; G lies at distance d ahead of A. A ball caster carries the
front: massless and frictionless, it adds no constraint. Coordinates: x, y of
A, heading theta, wheel angles phiL, phiR. Constraints: the axle does not
slip sideways, and each wheel rolls without slipping (3 affine constraints,
n = 5). Gravity does no work on the plane (no potential term).

Steady motion: driving straight at wheel rate w (a parameter), forward
(w > 0) or backward (w < 0). With no motors the wheels roll freely: the robot
is a Chaplygin sleigh with wheel inertia, the heading rate obeying
omega' = -mc d u omega / J with u = r w the forward speed and
J = Ic + mc d^2 + 2 (Id + mw b^2) + 2 Iw b^2 / r^2 the yaw inertia about A
(wheels' spin coupled to yaw through rolling): forward motion with the mass
ahead of the axle is asymptotically stable, backward unstable.
"""

from __future__ import annotations

import sys
from pathlib import Path

import sympy as sp
from sympy.physics import mechanics as me

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from scene_output import write_example  # noqa: E402
from nhham.system.description import System  # noqa: E402
from nhham.system.mechanics import from_mechanics  # noqa: E402

VALUES = {"mc": 4.0, "Ic": 0.08, "mw": 0.3, "Iw": 0.0015, "Id": 0.001, "r": 0.1, "b": 0.15,
          "d": 0.05, "w": 5.0}


def build(values=None):
    """The nhham System of the robot, from a sympy.physics.mechanics.System."""
    x, y, theta, phiL, phiR = me.dynamicsymbols("x y theta phiL phiR")
    mc, Ic, mw, Iw, Id, r, b, d = sp.symbols("mc Ic mw Iw Id r b d")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    C = N.orientnew("C", "Axis", [theta, N.z])          # chassis: C.x forward, C.y left
    WL = C.orientnew("WL", "Axis", [phiL, C.y])
    WR = C.orientnew("WR", "Axis", [phiR, C.y])
    A = O.locatenew("A", x * N.x + y * N.y)
    G = A.locatenew("G", d * C.x)
    PL = A.locatenew("PL", b * C.y)
    PR = A.locatenew("PR", -b * C.y)
    bodies = [
        me.RigidBody("chassis", G, C, mc, (me.inertia(C, 0, 0, Ic), G)),
        me.RigidBody("left_wheel", PL, WL, mw, (me.inertia(C, Id, Iw, Id), PL)),
        me.RigidBody("right_wheel", PR, WR, mw, (me.inertia(C, Id, Iw, Id), PR)),
    ]
    vA = A.pos_from(O).dt(N)
    # wheel contact points: r below the wheel centres; material velocity there = 0
    def contact(P, W):
        return P.pos_from(O).dt(N) + me.cross(W.ang_vel_in(N), -r * N.z)
    msys = me.System(N, O)
    msys.add_coordinates(x, y, theta, phiL, phiR)
    msys.add_bodies(*bodies)
    msys.add_nonholonomic_constraints(
        vA.dot(C.y), contact(PL, WL).dot(C.x), contact(PR, WR).dot(C.x))
    system = from_mechanics(msys, parameters=dict(values or VALUES),
                            name="differential-drive robot with caster")
    # The same expressions, tidied (small: trigsimp is cheap here).
    return System(system.coordinates, sp.trigsimp(sp.expand(system.lagrangian)),
                  constraints=[sp.trigsimp(sp.expand(c)) for c in system.constraints],
                  parameters=dict(values or VALUES), name=system.name)


STEADY = {"x": "0", "y": "0", "theta": "0", "phiL": "0", "phiR": "0",
          "x_dot": "r*w", "y_dot": "0", "theta_dot": "0", "phiL_dot": "w", "phiR_dot": "w"}

HEADER = """\
# A differential-drive robot with a ball caster (written by examples/make_differential_drive.py
# from a sympy.physics.mechanics.System). x, y: axle midpoint; theta heading; phiL, phiR wheel
# angles; the centre of mass is d ahead of the axle. No side slip of the axle, both wheels
# roll: n = 5, m = 3.
#
# What `nhham classify` reports: C regular on M_1 (rank 3, exact), one stage, determined, no
#   free multipliers, not integrable; on T*Q 1 first class, 2 second class (~3 s).
# What `nhham linearize` finds about the [steady] straight drive at wheel rate w: neutral
#   x, y, theta, phiL, phiR and the speed (d/dw); one eigenvalue -mc d r w / J with
#   J = Ic + mc d^2 + 2 (Id + mw b^2) + 2 Iw b^2 / r^2 (the Chaplygin sleigh with wheel inertia,
#   derived in the script's docstring; tests/system/test_mechanics_models.py): stable driving
#   forward (w > 0, mass ahead of the axle), unstable backward; `--sweep w=-5:5:11` finds
#   the real crossing at w = 0.
"""


def main(argv):
    w, r, b = VALUES["w"], VALUES["r"], VALUES["b"]
    initial = {"x": 0.0, "y": 0.0, "theta": 0.0, "phiL": 0.0, "phiR": 0.0,
               "x_dot": r * (w + 1.5 * w) / 2, "y_dot": 0.0,
               "theta_dot": r * (1.5 * w - w) / (2 * b), "phiL_dot": w, "phiR_dot": 1.5 * w}
    write_example(argv, "differential_drive.toml", HEADER, build(), initial=initial,
                  steady=STEADY)


if __name__ == "__main__":
    main(sys.argv)
