"""Write the scene of the rattleback, built with sympy.physics.mechanics.

Usage::

    python examples/make_rattleback.py [PATH]

writes ``examples/rattleback.toml`` (or PATH; ``-`` for stdout).

A rigid body whose bottom is the ellipsoid x^2/a^2 + y^2/b^2 + z^2/c^2 = 1 of its body
frame B (centre E), rolling without slipping on a horizontal plane under gravity g. The
mass centre G lies on the axis B.z at height h above the lowest point (0, 0, -c) of the
ellipsoid; the central inertia has the products I12 in the plane B.x, B.y (the principal
axes of inertia turned against the ellipsoid's: the rattleback's asymmetry).
Orientation: body-fixed z-x-y angles (yaw, roll, pitch) of B; x, y: the mass centre.
With n = N.z in B, the lowest point of the ellipsoid is P = E - A n / s (A = diag(a^2,
b^2, c^2), s = sqrt(n . A n)), E is at height s and G at height s + (h - c) n_3
(a function of the angles: no holonomic constraint). L = T - V from
``Lagrangian(N, body)`` with V = m g z_G; the rolling constraints say that the body's
point at P has no horizontal velocity: v_G + omega x (P - G) = 0 along N.x and N.y (its
vertical component holds identically). The declared symmetry is the rotation about the
vertical, which turns the yaw and the mass centre together.
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

VALUES = {"m": 1.0, "g": 9.81, "a": 0.1, "b": 0.02, "c": 0.025, "h": 0.008,
          "I11": 1.5e-4, "I22": 1.8e-3, "I33": 1.75e-3, "I12": -1.5e-4, "w": 40.0}


def geometry(N, B, a, b, c, h):
    """(z_G, P - G): the mass centre's height and the contact point from G, as vectors."""
    n1, n2, n3 = (N.z.dot(B.x), N.z.dot(B.y), N.z.dot(B.z))
    s = sp.sqrt(a ** 2 * n1 ** 2 + b ** 2 * n2 ** 2 + c ** 2 * n3 ** 2)
    zG = s + (h - c) * n3
    PG = -(a ** 2 * n1 * B.x + b ** 2 * n2 * B.y + c ** 2 * n3 * B.z) / s - (h - c) * B.z
    return zG, PG


def build(values=None):
    """The nhham System of the rattleback."""
    yaw, roll, pitch, x, y = me.dynamicsymbols("yaw roll pitch x y")
    m, g, a, b, c, h, I11, I22, I33, I12 = sp.symbols("m g a b c h I11 I22 I33 I12")
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Body", [yaw, roll, pitch], "ZXY")
    O = me.Point("O")
    O.set_vel(N, 0)
    zG, PG = geometry(N, B, a, b, c, h)
    G = O.locatenew("G", x * N.x + y * N.y + zG * N.z)
    G.set_vel(N, G.pos_from(O).dt(N))
    inertia = me.inertia(B, I11, I22, I33, I12, 0, 0)
    body = me.RigidBody("body", G, B, m, (inertia, G))
    body.potential_energy = m * g * zG
    L = me.Lagrangian(N, body)
    contact = G.vel(N) + B.ang_vel_in(N).cross(PG)
    nonhol = [contact.dot(N.x), contact.dot(N.y)]
    return from_mechanics(L, [yaw, roll, pitch, x, y], nonhol_coneqs=nonhol,
                          parameters=dict(values or VALUES), name="rattleback")


HEADER = """\
# The rattleback (written by examples/make_rattleback.py from a sympy.physics.mechanics
# model): a body with an ellipsoidal bottom (semi-axes a, b, c) rolling without slipping
# on a horizontal plane; mass centre at height h above the lowest point, central inertia
# with the product I12 (principal axes of inertia turned against the ellipsoid's).
# yaw, roll, pitch: body-fixed z-x-y angles; x, y: the mass centre. n = 5, m = 2.
# The parameters are this scene's own (of the size of a toy rattleback), not Kane &
# Levinson's (1982) numbers.
#
# The [symmetry] is the rotation about the vertical (yaw with the mass centre); the
# [steady] motion, upright spin at rate w, moves along it: a relative equilibrium.
# What `nhham linearize` reports: the generator leaves L and the rolling constraints
#   invariant (exact); v = w xi(q), w = 40; the state matrix of X - w Xi in co-moving
#   variables (roll, pitch, x_dot, y_dot; yaw, yaw_dot and the translations x, y divided
#   out, the block of x, y turning at +-40i); eigenvalues -7.79955071461 +- 31.2539415227i,
#   -16.6853003465 +- 50.2457307462i: asymptotically stable. At w = -40 (--set w=-40) the
#   negatives (time reversal): unstable. At w = 0: +-19.0361156878i, +-47.03879623i.
# `nhham linearize --sweep w=-100:100:41`: stable for w above w_c = 23.5599084053 (the
#   crossing to Re < 0 of the eigenvalue pair +-i w_c); the other direction is never
#   stable: one pair has Re > 0 for -w_c < w < 0, both below -w_c. At w = 0 (rocking
#   without spin, Re = 0) the two pairs exchange: crossings at -w_c, 0, 0 and w_c.
# Independent values: a KanesMethod model of the same body in body-frame speeds
#   (tests/numerics/rattleback_kane.py) gives the same four eigenvalues to 1e-8 at
#   w = +-40 and w_c = 23.559908405269 (tests/numerics/test_relative_equilibria.py).
"""


def main(argv):
    steady = {"yaw": 0.0, "roll": 0.0, "pitch": 0.0, "x": 0.0, "y": 0.0,
              "yaw_dot": "w", "roll_dot": 0.0, "pitch_dot": 0.0, "x_dot": 0.0, "y_dot": 0.0}
    write_example(argv, "rattleback.toml", HEADER, build(), steady=steady,
                  symmetry={"yaw": "1", "x": "-y", "y": "x"})


if __name__ == "__main__":
    main(sys.argv)
