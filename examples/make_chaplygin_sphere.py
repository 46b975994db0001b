"""Write the scene of the Chaplygin sphere, built with sympy.physics.mechanics.

Usage::

    python examples/make_chaplygin_sphere.py [PATH]

writes ``examples/chaplygin_sphere.toml`` (or PATH; ``-`` for stdout).

Chaplygin's ball: a sphere of radius r and mass m whose mass centre is its geometric
centre but whose principal moments I1, I2, I3 differ, rolling without slipping on a
horizontal plane. Orientation: body-fixed z-x-y angles (yaw, pitch, roll) of the body
frame B; x, y: the centre, at height r. L = T (the centre's height is constant, so
gravity does no work), from ``Lagrangian(N, ball)``; the rolling constraints say that
the material point at the contact, centre + omega x (-r N.z), has zero velocity
(two affine constraints; the vertical component vanishes identically).
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

VALUES = {"m": 1.0, "r": 0.5, "I1": 0.08, "I2": 0.1, "I3": 0.12}


def build(values=None, twist: bool = True):
    """The nhham System of the Chaplygin sphere (parameters m, r, I1, I2, I3); with
    ``twist=False`` the rubber ball (no spin about the vertical either)."""
    yaw, pitch, roll, x, y = me.dynamicsymbols("yaw pitch roll x y")
    m, r, I1, I2, I3 = sp.symbols("m r I1 I2 I3")
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Body", [yaw, pitch, roll], "ZXY")
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y + r * N.z)
    C.set_vel(N, C.pos_from(O).dt(N))
    ball = me.RigidBody("ball", C, B, m, (me.inertia(B, I1, I2, I3), C))
    L = me.Lagrangian(N, ball)
    contact = C.vel(N) + B.ang_vel_in(N).cross(-r * N.z)
    nonhol = [contact.dot(N.x), contact.dot(N.y)]
    if not twist:
        nonhol.append(sp.simplify(B.ang_vel_in(N).dot(N.z)))
    return from_mechanics(L, [yaw, pitch, roll, x, y], nonhol_coneqs=nonhol,
                          parameters=dict(values or VALUES),
                          name="Chaplygin sphere" if twist else "rubber ball")


HEADER = """\
# The Chaplygin sphere (written by examples/make_chaplygin_sphere.py from a
# sympy.physics.mechanics model): a ball of radius r, mass centre at its geometric centre,
# principal moments I1, I2, I3 all different, rolling without slipping on a plane.
# yaw, pitch, roll: body-fixed z-x-y angles; x, y: the centre. n = 5, m = 2.
#
# What `nhham classify` reports: C regular on M_1 (rank 2, proved at an exact point), one
#   stage, determined, no free multipliers; not integrable (rolling); on T*Q the bracket
#   matrix of the two constraints has rank 2 at an exact point: 0 first class, 2 second
#   class (the same rank from a numpy bracket matrix: tests/lagrangian/test_tangency.py).
# `nhham linearize`: no [steady] table. The sphere's steady motions move coordinates the
#   dynamics depends on (spinning about a vertical principal axis turns the yaw, which turns
#   the rolling constraints; rolling about a horizontal one turns the roll), so no constant
#   state matrix describes them in this chart: linearize refuses such a [steady] table with
#   that message (tests/cli/test_linearize_command.py), unless a [symmetry] table declares
#   the rotation about the vertical (yaw = "1", x = "-y", y = "x"): then the spin at rate w
#   about a vertical principal axis is a relative equilibrium, linearised in co-moving
#   variables: +-i w and +-w sqrt((I2 - I3)(I3 - I1)/((I1 + m r^2)(I2 + m r^2))) by hand
#   (tests/journeys/test_relative_linearize.py).
# Energy is conserved (L = T, the constraints are linear). Reference for the model:
#   S. A. Chaplygin, "On a ball's rolling on a horizontal plane" (1903); A. V. Borisov,
#   I. S. Mamaev, "Rolling of a rigid body on a plane and sphere", Regul. Chaotic Dyn. 7 (2002).
# What `nhham reduce` finds: symmetry x, y (the contact point), shape yaw, pitch, roll; the
#   reduced field lifted back is P(xi_L) at 30-digit points (6 s); the yaw momentum
#   equation has rate 0: p_yaw, the vertical angular momentum about the contact point
#   (M, gamma), is conserved.
# Second step: `nhham reduce --symmetry x,y --level yaw=0` reduces yaw on the level
#   (M, gamma) = 0 (the results hold on that level only): shape pitch, roll, J2 = p_yaw = 0,
#   gyroscopic form T^T G T; the lifted field is P(xi_L) at points of M_1 on the level.
#   There theta ^ Omega_nh = -d Omega_nh solves to theta = d ln (1 - D (gamma, A gamma))^(-1/2)
#   (D = m r^2, A = (I + D E)^-1, gamma the vertical in the body frame), Borisov and
#   Mamaev's multiplier (Math. Notes 70 (2001)), decided exactly in
#   tests/lagrangian/test_chaplygin_stages.py. `nhham hamiltonize --symmetry x,y --level
#   yaw=0` finds it in 23 s: hamiltonizable, f = 1/sqrt(P) with P = prod(I_i + D) (1 - D
#   (gamma, A gamma)) (theta read off Omega_nh, d theta = 0 by the normal form modulo
#   sin^2 + cos^2 = 1).
"""


def main(argv):
    r = VALUES["r"]
    # Rolling along x with the ball spinning about N.y at rate 2 (and a little yaw rate).
    initial = {"yaw": 0.0, "pitch": 0.0, "roll": 0.0, "x": 0.0, "y": 0.0,
               "yaw_dot": 0.3, "pitch_dot": 0.0, "roll_dot": 2.0, "x_dot": 2.0 * r,
               "y_dot": 0.0}
    write_example(argv, "chaplygin_sphere.toml", HEADER, build(), initial=initial)


if __name__ == "__main__":
    main(sys.argv)
