"""Systems with parameters whose exceptional cases are derived by hand in their
docstrings: shared by the tests of the verdicts (tests/verdict) and of the exceptional data
(tests/lagrangian/test_exceptional.py)."""

from __future__ import annotations

import nhham


def paper_3_1(values=None):
    """Example 3.1 with a parameter in front of each term.

    L = (a v1^2 + b v2^2 - c v3^2)/2, phi = v2 + e v3. W = diag(a, b, -c), mu = (0, 1, e),
    C = -mu W^-1 mu^T = -(1/b - e^2/c) = -(c - b e^2)/(b c).

    * generic (c != b e^2): C regular (rank 1), determined, 1 stage; mu constant, so the
      distribution is integrable; one final constraint, B = 0: 1 first class.
    * c = b e^2: C = 0; xi_L(phi) = 0 (no forces), so M_f = M_1 and lambda_1 is free:
      underdetermined, 1 stage, 1 free multiplier, 1 first class.
    * a = 0, b = 0 or c = 0: W singular (dropped when a, b, c are declared positive; with
      c = b e^2 also e = 0 gives c = 0).
    """
    return nhham.System(["q1", "q2", "q3"], "(a*q1_dot**2 + b*q2_dot**2 - c*q3_dot**2)/2",
                        ["q2_dot + e*q3_dot"], parameters=values or ["a", "b", "c", "e"],
                        name="paper 3.1 with parameters")


def paper_3_2(values=None):
    """Example 3.2 with a parameter in front of each term.

    L = (a v1^2 + b v2^2 - c v3^2)/2 + d q1^2/2, phi = v1 + e v3, F = (d q1, 0, 0).
    C = -(1/a - e^2/c) = -(c - a e^2)/(a c).

    * generic: regular, determined, 1 stage, integrable, 1 first class.
    * c = a e^2, d != 0: C = 0 and xi_L(phi) = F_1/a - e F_3/c = d q1/a: secondary q1 = 0;
      on M_2 xi_L(q1) = v1: secondary v1 = 0; on M_3 Z(v1) = -1/a != 0, rank 1: determined,
      3 stages; final constraints (phi, q1, v1): {q1, v1} second class, 1 first class.
    * c = a e^2, d = 0: xi_L(phi) = 0: underdetermined, 1 stage, 1 free multiplier.
    """
    return nhham.System(["q1", "q2", "q3"],
                        "(a*q1_dot**2 + b*q2_dot**2 - c*q3_dot**2)/2 + d*q1**2/2",
                        ["q1_dot + e*q3_dot"], parameters=values or ["a", "b", "c", "d", "e"],
                        name="paper 3.2 with parameters")


def rolling_disc(values=None):
    """The vertical rolling disc, the rolling written through the radius R.

    phi_1 = x' - R cos(theta) phi', phi_2 = y' - R sin(theta) phi'. ker mu is spanned by
    X_1 = d/dtheta and X_2 = d/dphi + R cos(theta) d/dx + R sin(theta) d/dy, and
    [X_1, X_2] = R(-sin(theta) d/dx + cos(theta) d/dy) is outside ker mu unless R = 0.

    * generic: regular (rank 2), determined, not integrable, 2 first class.
    * R = 0 (x' = y' = 0: the disc spins in place): integrable, otherwise the same.
    * C = -(diag(1/m) + (R^2/I2) (cos, sin)(cos, sin)^T) has det (I2 + m R^2)/(m^2 I2):
      no real zero with m, I2 > 0 (dropped).
    """
    return nhham.System(["x", "y", "theta", "phi"],
                        "m*(x_dot**2 + y_dot**2)/2 + I1*theta_dot**2/2 + I2*phi_dot**2/2",
                        ["x_dot - R*cos(theta)*phi_dot", "y_dot - R*sin(theta)*phi_dot"],
                        parameters=values or ["m", "I1", "I2", "R"], name="rolling disc")


def two_bodies(values=None):
    """Two rotors geared 1:1, with kinetic terms of opposite sign, and a spring on the first.

    For a positive-definite W, C = -mu W^-1 mu^T is negative definite, so a singular C
    needs an indefinite kinetic term (as in the paper's own examples):
    L = (I1 x1'^2 - I2 x2'^2)/2 - k x1^2/2, phi = x1' - x2'. C = -(1/I1 - 1/I2).

    * generic (I1 != I2): regular, determined, 1 stage, 1 first class.
    * I1 = I2, k != 0: xi_L(phi) = -k x1/I1 -> x1 = 0, then x1' = 0, then Z(x1') = -1/I1:
      determined, 3 stages, 2 second class, 1 first class.
    * I1 = I2, k = 0: underdetermined, 1 free multiplier.
    """
    return nhham.System(["x1", "x2"], "(I1*x1_dot**2 - I2*x2_dot**2)/2 - k*x1**2/2",
                        ["x1_dot - x2_dot"], parameters=values or ["I1", "I2", "k"],
                        name="two bodies")


def key(v):
    return (v.status, v.regular, v.rank_C, v.stages, v.free_multipliers, v.integrable,
            v.first_class, v.second_class)
