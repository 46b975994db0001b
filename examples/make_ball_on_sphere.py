"""Write the scene of a ball rolling on a fixed sphere: a rolling constraint on a curved
surface, the contact point on the sphere a holonomic constraint no coordinate enters
linearly.

Usage::

    python examples/make_ball_on_sphere.py [PATH]

writes ``examples/ball_on_sphere.toml`` (or PATH; ``-`` for stdout).

A homogeneous ball (mass m, radius r, inertia 2/5 m r^2) rolls without slipping on the
outside of a fixed sphere of radius R centred at the origin. Coordinates: the contact point
P = (x, y, z), on the sphere x^2 + y^2 + z^2 = R^2 (holonomic: M_1 is curved), and the
ball's orientation by z-x-z Euler angles (alpha, beta, gamma), angular velocity
omega = alpha' e_z + beta' e_1 + gamma' e_3 (e_1 the line of nodes, e_3 the body axis).
The centre is C = (1 + r/R) P. Rolling: the material point of the ball at P has no
velocity, v_C + omega x (P - C) = 0; its normal component is the lift of the sphere
constraint, so the scene keeps the components along the unit tangent vectors
e_z x P / rho (east) and P x east / R (north), rho = sqrt(x^2 + y^2): undefined at the poles
x = y = 0 (no tangent frame of the sphere is regular everywhere; unnormalised ones vanish
there and give M_1 a spurious component of every velocity at the poles). n = 6, m = 3.
"""

from __future__ import annotations

import sys
from pathlib import Path

import sympy as sp

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from scene_output import write_example  # noqa: E402
from nhham import System  # noqa: E402

VALUES = {"m": 1.0, "r": 0.1, "R": 1.0, "g": 9.81}


def ball_on_sphere() -> System:
    """The system: L = T - V of the ball, the sphere and the rolling constraints."""
    x, y, z, al, be, ga = q = sp.symbols("x y z alpha beta gamma")
    xd, yd, zd, ald, bed, gad = sp.symbols("x_dot y_dot z_dot alpha_dot beta_dot gamma_dot")
    m, r, R, g = sp.symbols("m r R g")
    nodes = sp.Matrix([sp.cos(al), sp.sin(al), 0])
    axis = sp.Matrix([sp.sin(be) * sp.sin(al), -sp.sin(be) * sp.cos(al), sp.cos(be)])
    omega = ald * sp.Matrix([0, 0, 1]) + bed * nodes + gad * axis
    P = sp.Matrix([x, y, z])
    vC = (1 + r / R) * sp.Matrix([xd, yd, zd])
    L = (m * vC.dot(vC) / 2 + sp.Rational(2, 5) * m * r**2 * sp.expand(omega.dot(omega)) / 2
         - m * g * (1 + r / R) * z)
    slip = vC + omega.cross(-(r / R) * P)
    rho = sp.sqrt(x**2 + y**2)
    east = sp.Matrix([0, 0, 1]).cross(P) / rho
    north = P.cross(east) / R
    rolling = [sp.expand(slip.dot(east)), sp.expand(slip.dot(north))]
    return System(list(q), sp.simplify(L), rolling,
                  holonomic=[x**2 + y**2 + z**2 - R**2],
                  parameters={sp.Symbol(k): v for k, v in VALUES.items()},
                  name="ball rolling on a sphere")


HEADER = """# A ball rolling on a fixed sphere (written by examples/make_ball_on_sphere.py): contact
# point (x, y, z) on x^2 + y^2 + z^2 = R^2 (curved M_1), orientation by z-x-z Euler angles
# (alpha, beta, gamma); the material point at the contact does not move (its east and
# north components as constraints, undefined at the poles; the normal one is the sphere's
# lift). n = 6, m = 3.
# What `nhham classify` reports: C regular on M_1 (rank 3), one stage (M_f = M_1),
#   determined, not integrable; on T*Q 0 first class, 4 second class. Source: every
#   decision proved at smooth points of M_1 over F_p, with the parameters at their values.
"""

if __name__ == "__main__":
    write_example(sys.argv, "ball_on_sphere.toml", HEADER, ball_on_sphere())
