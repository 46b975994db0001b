"""Write the scene of a four-bar linkage on a rolling cart: a closed loop (a curved
configuration space) with a rolling constraint.

Usage::

    python examples/make_four_bar_cart.py [PATH]

writes ``examples/four_bar_cart.toml`` (or PATH; ``-`` for stdout).

The cart (mass M, yaw inertia J) moves on the floor like a knife edge: position (x, y),
heading psi, no sideways slip, -x' sin(psi) + y' cos(psi) = 0. Standing on it, in the
vertical plane through the heading, a four-bar linkage: the ground link is the cart (pivots
O and D a distance d apart along the heading), the crank (length a, angle theta1 from the
heading), the coupler (b, theta2) and the rocker (c, theta3); each link a point mass m at its
midpoint. The loop closes with

    a cos(theta1) + b cos(theta2) - c cos(theta3) - d = 0,
    a sin(theta1) + b sin(theta2) - c sin(theta3) = 0,

two holonomic constraints that no coordinate enters linearly: M_1 is curved, and nhham
draws its points over F_p (two dependent angles from a Groebner basis). n = 6, m = 3 (two
lifts and the rolling constraint).
"""

from __future__ import annotations

import sys
from pathlib import Path

import sympy as sp

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from scene_output import write_example  # noqa: E402
from nhham import System  # noqa: E402

VALUES = {"M": 4.0, "J": 0.3, "m": 0.5, "a": 0.2, "b": 0.5, "c": 0.4, "d": 0.45, "g": 9.81}


def four_bar_cart() -> System:
    """The system: L = T - V of the cart and the three link masses, the loop closure and
    the cart's rolling constraint."""
    x, y, psi, t1, t2, t3 = q = sp.symbols("x y psi theta1 theta2 theta3")
    qd = sp.symbols("x_dot y_dot psi_dot theta1_dot theta2_dot theta3_dot")
    M, J, m, a, b, c, d, g = sp.symbols("M J m a b c d g")
    heading = sp.Matrix([sp.cos(psi), sp.sin(psi), 0])
    up = sp.Matrix([0, 0, 1])
    base = sp.Matrix([x, y, 0])

    def at(s, h):  # a point of the linkage's plane: s along the heading, h up
        return base + s * heading + h * up

    crank = (a * sp.cos(t1), a * sp.sin(t1))
    joint = (crank[0] + b * sp.cos(t2), crank[1] + b * sp.sin(t2))
    masses = [at(crank[0] / 2, crank[1] / 2),
              at((crank[0] + joint[0]) / 2, (crank[1] + joint[1]) / 2),
              at(d + c * sp.cos(t3) / 2, c * sp.sin(t3) / 2)]
    T = (M * (qd[0] ** 2 + qd[1] ** 2) + J * qd[2] ** 2) / 2
    V = 0
    for p in masses:
        v = p.jacobian(q) * sp.Matrix(qd)
        T += m * sp.expand(v.dot(v)) / 2
        V += m * g * p[2]
    loop = [a * sp.cos(t1) + b * sp.cos(t2) - c * sp.cos(t3) - d,
            a * sp.sin(t1) + b * sp.sin(t2) - c * sp.sin(t3)]
    rolling = [-qd[0] * sp.sin(psi) + qd[1] * sp.cos(psi)]
    return System(list(q), sp.simplify(T) - V, rolling, holonomic=loop,
                  parameters={sp.Symbol(k): v for k, v in VALUES.items()},
                  name="four-bar linkage on a rolling cart")


HEADER = """# A four-bar linkage on a rolling cart (written by examples/make_four_bar_cart.py): the
# cart (x, y, psi) rolls like a knife edge, the linkage (crank theta1, coupler theta2,
# rocker theta3) stands in the vertical plane of the heading and closes its loop with two
# holonomic constraints no coordinate enters linearly: M_1 is curved. n = 6, m = 3.
# What `nhham classify` reports: C regular on M_1 (rank 3), one stage (M_f = M_1),
#   determined, not integrable; on T*Q 1 first class, 4 second class (5 constraints: an
#   antisymmetric 5 x 5 bracket matrix has rank at most 4, and 4 is found). Source: every
#   decision proved at smooth points of M_1 over F_p (the two dependent angles from a
#   Groebner basis), with the parameters at their values; no warning but the size of the
#   first-class combination's closed form.
"""

if __name__ == "__main__":
    write_example(sys.argv, "four_bar_cart.toml", HEADER, four_bar_cart())
