"""Write the scene of the rubber ball (Chaplygin's ball rolling without slipping or
twisting), built with sympy.physics.mechanics.

Usage::

    python examples/make_rubber_ball.py [PATH]

writes ``examples/rubber_ball.toml`` (or PATH; ``-`` for stdout).

The body of ``make_chaplygin_sphere.py`` (radius r, mass m, mass centre at the centre,
principal moments I1, I2, I3; body-fixed z-x-y angles yaw, pitch, roll; centre x, y) with a
third constraint: no spin about the vertical, omega . N.z = yaw' + sin(pitch) roll' = 0
(Ehlers, Koiller, Montgomery & Rios 2005, "rubber" rolling).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from make_chaplygin_sphere import VALUES, build as sphere  # noqa: E402
from scene_output import write_example  # noqa: E402


def build(values=None):
    """The nhham System of the rubber ball (parameters m, r, I1, I2, I3): the Chaplygin
    sphere's model (examples/make_chaplygin_sphere.py) with omega . N.z = 0 added."""
    return sphere(values, twist=False)


HEADER = """\
# The rubber ball (written by examples/make_rubber_ball.py from a sympy.physics.mechanics
# model): Chaplygin's ball (examples/chaplygin_sphere.toml: radius r, mass centre at the
# centre, principal moments I1, I2, I3) rolling without slipping AND without twisting
# (omega . N.z = yaw' + sin(pitch) roll' = 0). yaw, pitch, roll: body-fixed z-x-y angles;
# x, y: the centre. n = 5, m = 3.
#
# What `nhham reduce --symmetry x,y --then yaw` finds: step 1 reduces the contact point
#   x, y (the rolling constraints), leaving yaw' + sin(pitch) roll' = 0 on the shape space;
#   step 2 reduces yaw by it (A2 = (0, sin pitch), B2_(pitch,roll) = cos pitch), shape
#   (pitch, roll); the reduced field lifted back through both steps is P(xi_L) at 30-digit
#   points of M_1.
# Literature: Ehlers, Koiller, Montgomery & Rios (2005) state that the rubber ball is
#   Hamiltonizable. On this T*S (pitch, roll) theta ^ Omega_nh = -d Omega_nh solves to
#   theta = d ln (gamma, A gamma)^(-1/2) (gamma the vertical in the body frame, A =
#   (I + m r^2 E)^-1), decided exactly in tests/lagrangian/test_chaplygin_stages.py: the
#   conformal factor is f = (gamma, A gamma)^(-1/2) up to a constant, which is
#   (det of the reduced Legendre transform / cos^2 pitch)^(-1/2): Ehlers & Koiller's
#   invariant density ("Rubber rolling over a sphere", 2007) with p = (b/a - 1)/2 = -1/2
#   for a plane.
# `nhham hamiltonize --symmetry x,y --then yaw` reaches it in 7 s: hamiltonizable, f the
#   reciprocal square root of (gamma, A gamma) times a constant, Jacobiator 0 after.
"""


def main(argv):
    r = VALUES["r"]
    # Rolling along x about N.y at rate 2, no spin about the vertical.
    initial = {"yaw": 0.0, "pitch": 0.0, "roll": 0.0, "x": 0.0, "y": 0.0,
               "yaw_dot": 0.0, "pitch_dot": 0.0, "roll_dot": 2.0, "x_dot": 2.0 * r,
               "y_dot": 0.0}
    write_example(argv, "rubber_ball.toml", HEADER, build(), initial=initial)


if __name__ == "__main__":
    main(sys.argv)
