"""Independently derived reference values for the printed examples of
de León & Martín de Diego (1996), "Solving non-holonomic Lagrangian dynamics in
terms of almost product structures", Extracta Mathematicae 11 (1996) 325–347.

This module does NOT import nhham.  Every value below is written out by hand from
the conventions of ``DESIGN.md`` §2 (W_AB = d^2L/dv^A dv^B; omega_L = dq^A ^ dp_A;
i_{Z_i} omega_L = mu_i^v  =>  Z_i = -W^{AB} mu_iB d/dv^A; C_ij = Z_i(phi_j);
lambda^j = -C^{ij} xi_L(phi_i); P(xi_L) = xi_L + lambda^j Z_j;
P = id - Q, Q = C^{ij} Z_j (x) dphi_i), with W^{-1} and C^{-1} inverted by hand.
See ``docs/paper-errata.md`` for what the paper prints and where it is wrong.

Layout conventions of the returned objects:

* a coordinate ``q`` has velocity symbol ``q_dot``; all symbols are plain
  ``sympy.Symbol`` (no assumptions);
* vectors on TQ are 2n-component column Matrices in the order (q^1..q^n, v^1..v^n);
* ``'Z'`` is an m x 2n Matrix whose row i holds the components of Z_i;
* ``'omega'`` is the 2n x 2n matrix Omega with omega_L(X, Y) = X^T Omega Y;
* ``'P'`` / ``'P_on_M1'`` is the 2n x 2n matrix of the (1,1) tensor P acting on
  column vectors: (P X)^a = P[a, b] X^b (rows = output component, columns = input);
* ``'multipliers'`` is an m x 1 Matrix (lambda^1, ..., lambda^m).

The values were cross-checked (scripts outside the repository) against a
from-the-definitions symbolic computation (solving i_X Omega = dE_L etc. as
linear systems) and, for Examples 2.1 and 4.1, against
sympy.physics.mechanics.LagrangesMethod at random points of M_1 (agreement
better than 1e-12).
"""

import sympy as sp

__all__ = [
    "example_2_1",
    "remark_2_1",
    "example_3_1",
    "example_3_2",
    "example_4_1",
    "example_5_1",
]

_half = sp.Rational(1, 2)


def _vel(q):
    return sp.Symbol(f"{q.name}_dot")


def _grad(f, z):
    """Row of partial derivatives (components of df in the (q, v) basis)."""
    return sp.Matrix([[sp.diff(f, zi) for zi in z]])


# ---------------------------------------------------------------------------
# Example 2.1: vertical rolling disk
# ---------------------------------------------------------------------------

def example_2_1():
    """Vertical rolling disk (paper Example 2.1).

    L = (m xd^2 + m yd^2 + I1 t1d^2 + I2 t2d^2)/2, W = diag(m, m, I1, I2),
    W^{-1} = diag(1/m, 1/m, 1/I1, 1/I2).  mu_1 = (1, 0, 0, -R c), mu_2 = (0, 1, 0, -R s)
    with c = cos(theta1), s = sin(theta1).  Z_i = -W^{-1} mu_i:
    Z_1 = -(1/m) d/dxd + (R c/I2) d/dt2d, Z_2 = -(1/m) d/dyd + (R s/I2) d/dt2d.
    C = -mu W^{-1} mu^T = -(1/m) Id - (R^2/I2) n n^T, n = (c, s); by Sherman-Morrison
    C^{-1} = -m (Id - k n n^T), k = m R^2/(I2 + m R^2).  xi_L = (v, 0) (free motion),
    xi_L(phi_1) = R s t1d t2d, xi_L(phi_2) = -R c t1d t2d, so
    lambda = -C^{-1} xi_L(phi) = (m R t1d t2d s, -m R t1d t2d c)  (on all of TQ):
    the paper's printed P(xi_L) is correct.  P(xi_L) accelerations:
    xdd = -R s t1d t2d, ydd = R c t1d t2d, t1dd = t2dd = 0.
    """
    x, y, th1, th2 = sp.symbols("x y theta1 theta2")
    m, I1, I2, R = sp.symbols("m I1 I2 R")
    q = [x, y, th1, th2]
    xd, yd, t1d, t2d = v = [_vel(s) for s in q]
    z = q + v
    c, s = sp.cos(th1), sp.sin(th1)

    L = _half * (m * xd**2 + m * yd**2 + I1 * t1d**2 + I2 * t2d**2)
    E = L  # no potential: E_L = v dL/dv - L = L
    W = sp.diag(m, m, I1, I2)
    omega = sp.BlockMatrix([[sp.zeros(4), W], [-W, sp.zeros(4)]]).as_explicit()
    xi = sp.Matrix([xd, yd, t1d, t2d, 0, 0, 0, 0])

    phi = [xd - R * c * t2d, yd - R * s * t2d]
    mu = sp.Matrix([[1, 0, 0, -R * c], [0, 1, 0, -R * s]])
    Z = sp.Matrix([
        [0, 0, 0, 0, -1 / m, 0, 0, R * c / I2],
        [0, 0, 0, 0, 0, -1 / m, 0, R * s / I2],
    ])
    C = sp.Matrix([
        [-1 / m - R**2 * c**2 / I2, -R**2 * c * s / I2],
        [-R**2 * c * s / I2, -1 / m - R**2 * s**2 / I2],
    ])
    k = m * R**2 / (I2 + m * R**2)
    C_inv = -m * sp.Matrix([[1 - k * c**2, -k * c * s], [-k * c * s, 1 - k * s**2]])
    xi_phi = sp.Matrix([R * s * t1d * t2d, -R * c * t1d * t2d])
    lam = sp.Matrix([m * R * t1d * t2d * s, -m * R * t1d * t2d * c])
    Pxi = sp.Matrix([xd, yd, t1d, t2d,
                     -R * s * t1d * t2d, R * c * t1d * t2d, 0, 0])

    # P = id - Q, Q = C^{ij} Z_j (x) dphi_i  (C symmetric), written as
    # Q[a, b] = sum_ij Z_j^a C^{ij} dphi_i,b.
    dphi = sp.Matrix.vstack(_grad(phi[0], z), _grad(phi[1], z))
    Q = Z.T * C_inv * dphi
    P = (sp.eye(8) - Q).applyfunc(sp.simplify)

    on_M1 = {xd: R * c * t2d, yd: R * s * t2d}
    return {
        "coordinates": q,
        "velocities": v,
        "parameters": [m, I1, I2, R],
        "lagrangian": L,
        "energy": E,
        "W": W,
        "omega": omega,
        "xi": xi,
        "phi": phi,
        "mu": mu,
        "Z": Z,
        "C": C,
        "C_inv": C_inv,
        "xi_phi": xi_phi,
        "multipliers": lam,
        "projected_field": Pxi,
        "P": P,
        "M1_substitution": on_M1,
    }


def remark_2_1():
    """Remark 2.1 on the rolling disk with phibar = D phi, D = rotation by theta1.

    phibar_1 = c phi_1 + s phi_2 = c xd + s yd - R t2d (rolling),
    phibar_2 = -s phi_1 + c phi_2 = -s xd + c yd (no side slip).
    D depends on q only, so Zbar_j = D_j^i Z_i and Cbar = D C D^T = diag(-1/m - R^2/I2, -1/m)
    (D n = e_1).  dphibar = D dphi + phi dD, so Qbar = Q exactly on M1 but not off M1
    (e.g. the d/dtheta1 column picks up phibar_2, -phibar_1 terms).
    'P_bar' is given on all of TQ; 'P_bar_on_M1' equals example_2_1()['P'] on M1.
    """
    d = example_2_1()
    x, y, th1, th2 = d["coordinates"]
    xd, yd, t1d, t2d = d["velocities"]
    m, I1, I2, R = d["parameters"]
    z = d["coordinates"] + d["velocities"]
    c, s = sp.cos(th1), sp.sin(th1)
    D = sp.Matrix([[c, s], [-s, c]])
    phibar = [c * xd + s * yd - R * t2d, -s * xd + c * yd]
    Zbar = sp.Matrix([
        [0, 0, 0, 0, -c / m, -s / m, 0, R / I2],
        [0, 0, 0, 0, s / m, -c / m, 0, 0],
    ])
    Cbar = sp.diag(-1 / m - R**2 / I2, -1 / m)
    Cbar_inv = sp.diag(-m * I2 / (I2 + m * R**2), -m)
    dphibar = sp.Matrix.vstack(_grad(phibar[0], z), _grad(phibar[1], z))
    Pbar = (sp.eye(8) - Zbar.T * Cbar_inv * dphibar).applyfunc(sp.simplify)
    on_M1 = d["M1_substitution"]
    return {
        "D": D,
        "phi_bar": phibar,
        "Z_bar": Zbar,
        "C_bar": Cbar,
        "C_bar_inv": Cbar_inv,
        "P_bar": Pbar,
        "P_bar_on_M1": Pbar.subs(on_M1).applyfunc(sp.simplify),
        "P_on_M1": d["P"].subs(on_M1).applyfunc(sp.simplify),
        "M1_substitution": on_M1,
    }


# ---------------------------------------------------------------------------
# Examples 3.1 and 3.2: Lorentzian kinetic energy, singular C
# ---------------------------------------------------------------------------

def example_3_1():
    """Example 3.1: L = (v1^2 + v2^2 - v3^2)/2, phi = v2 + v3.

    W = diag(1, 1, -1) = W^{-1}; mu = (0, 1, 1); Z = -W^{-1} mu = -d/dv2 + d/dv3.
    E_L = L; xi_L = v^A d/dq^A (no forces).  C = Z(phi) = -1 + 1 = 0 and
    xi_L(phi) = 0 identically, so no secondary constraint: M_f = M_1, the multiplier
    is free, dynamics xi_L + lambda Z for any lambda ('underdetermined').
    (The paper's "xi_L = C" is a misprint: C is the Liouville field v^A d/dv^A;
    what holds is J xi_L = C.)
    """
    q1, q2, q3 = q = list(sp.symbols("q1 q2 q3"))
    v1, v2, v3 = v = [_vel(s) for s in q]
    L = _half * (v1**2 + v2**2 - v3**2)
    W = sp.diag(1, 1, -1)
    omega = sp.BlockMatrix([[sp.zeros(3), W], [-W, sp.zeros(3)]]).as_explicit()
    xi = sp.Matrix([v1, v2, v3, 0, 0, 0])
    phi = v2 + v3
    Z = sp.Matrix([[0, 0, 0, 0, -1, 1]])
    return {
        "coordinates": q,
        "velocities": v,
        "parameters": [],
        "lagrangian": L,
        "energy": L,
        "W": W,
        "omega": omega,
        "xi": xi,
        "phi": [phi],
        "mu": sp.Matrix([[0, 1, 1]]),
        "Z": Z,
        "C": sp.Matrix([[0]]),
        "xi_phi": sp.Matrix([0]),
        "stages": [[phi]],
        "final_constraints": [phi],
        "multipliers": None,  # undetermined
        "free_multipliers": 1,
        "classification": "underdetermined",
        "dynamics_family": lambda lam: xi + lam * Z.T,
    }


def example_3_2():
    """Example 3.2: L = (v1^2 + v2^2 - v3^2)/2 + (q1)^2/2, phi = v1 + v3.

    W = diag(1, 1, -1); E_L = (v1^2 + v2^2 - v3^2)/2 - q1^2/2;
    xi^1 = W^{11} dL/dq1 = q1, so xi_L = v^A d/dq^A + q1 d/dv1.
    mu = (1, 0, 1); Z = -W^{-1} mu = -d/dv1 + d/dv3.
    Stage 1: Z(phi) = 0, xi_L(phi) = q1      -> psi = q1           (M_2)
    Stage 2: Z(psi) = 0, xi_L(psi) = v1      -> psi' = v1          (M_3)
    Stage 3: Z(psi') = -1 != 0 -> stop; lambda = -xi_L(psi')/Z(psi') = q1.
    M_3 = {v1 + v3 = 0, q1 = 0, v1 = 0} = {q1 = 0, v1 = 0, v3 = 0}; on M_3 lambda = 0
    and xi_L + q1 Z = v2 d/dq2.  (xi_L + q1 Z)(phi, psi, psi') = (q1, v1, 0): tangent on M_3.
    """
    q1, q2, q3 = q = list(sp.symbols("q1 q2 q3"))
    v1, v2, v3 = v = [_vel(s) for s in q]
    L = _half * (v1**2 + v2**2 - v3**2) + _half * q1**2
    E = _half * (v1**2 + v2**2 - v3**2) - _half * q1**2
    W = sp.diag(1, 1, -1)
    omega = sp.BlockMatrix([[sp.zeros(3), W], [-W, sp.zeros(3)]]).as_explicit()
    xi = sp.Matrix([v1, v2, v3, q1, 0, 0])
    phi = v1 + v3
    Z = sp.Matrix([[0, 0, 0, -1, 0, 1]])
    lam = q1
    Pxi = xi + lam * Z.T  # = (v1, v2, v3, 0, 0, q1)
    on_M3 = {q1: 0, v1: 0, v3: 0}
    return {
        "coordinates": q,
        "velocities": v,
        "parameters": [],
        "lagrangian": L,
        "energy": E,
        "W": W,
        "omega": omega,
        "xi": xi,
        "phi": [phi],
        "mu": sp.Matrix([[1, 0, 1]]),
        "Z": Z,
        "C": sp.Matrix([[0]]),
        "stages": [[phi], [q1], [v1]],
        "Z_of_stage_constraints": [0, 0, -1],
        "xi_of_stage_constraints": [q1, v1, q1],
        "final_constraints": [q1, v1, v3],
        "M3_substitution": on_M3,
        "multipliers": sp.Matrix([lam]),
        "multipliers_on_M3": sp.Matrix([0]),
        "projected_field": Pxi,
        "projected_field_on_M3": sp.Matrix([0, v2, 0, 0, 0, 0]),
        "classification": "determined",
    }


# ---------------------------------------------------------------------------
# Example 4.1: two particles joined by a rod (holonomic + nonholonomic)
# ---------------------------------------------------------------------------

def example_4_1():
    """Example 4.1: unit masses at (x1, y1), (x2, y2) joined by a rod of length l.

    (The paper's text says P1 = (x1, x2), P2 = (y1, y2); h1 and the potential only make
    sense with P1 = (x1, y1), P2 = (x2, y2), which is used here.)
    Order q = (x1, x2, y1, y2).  W = Id = W^{-1}; E_L = |v|^2/2 + g (y1 + y2);
    xi_L = v^A d/dq^A - g d/dy1d - g d/dy2d.  Write X = x2 - x1, Y = y2 - y1,
    U = x2d - x1d, V = y2d - y1d, Sx = x1d + x2d, Sy = y1d + y2d.
    phi_1 = h1^c = X U + Y V (the paper's printed form is equal to this),
    phi_2 = X Sy - Y Sx.  mu_1 = (-X, X, -Y, Y), mu_2 = (-Y, -Y, X, X).
    Z_i = -mu_i: Z_1 = X d/dx1d - X d/dx2d + Y d/dy1d - Y d/dy2d,
                 Z_2 = Y d/dx1d + Y d/dx2d - X d/dy1d - X d/dy2d   (as printed).
    C = -mu mu^T = -2 (X^2 + Y^2) Id  -> on M1 (X^2 + Y^2 = l^2): -2 l^2 Id (as printed).
    xi_L(phi_1) = U^2 + V^2, xi_L(phi_2) = U Sy - V Sx - 2 g X = 2 (x2d y1d - x1d y2d) - 2 g X.
    lambda = -C^{-1} xi_L(phi) = xi_L(phi) / (2 l^2) on M1:
      lambda^1 = (U^2 + V^2)/(2 l^2),  lambda^2 = (x2d y1d - x1d y2d - g X)/l^2.
    P(xi_L) = xi_L + lambda^1 Z_1 + lambda^2 Z_2 (the printed one is wrong).
    P on M1 = Id + (1/(2 l^2)) (Z_1^T dphi_1 + Z_2^T dphi_2), an 8 x 8 matrix.
    """
    x1, x2, y1, y2 = q = list(sp.symbols("x1 x2 y1 y2"))
    x1d, x2d, y1d, y2d = v = [_vel(s) for s in q]
    g, l = sp.symbols("g l")
    X, Y = x2 - x1, y2 - y1
    U, V = x2d - x1d, y2d - y1d
    Sx, Sy = x1d + x2d, y1d + y2d
    rho = X**2 + Y**2  # = l^2 on M1

    L = _half * (x1d**2 + x2d**2 + y1d**2 + y2d**2) - g * (y1 + y2)
    E = _half * (x1d**2 + x2d**2 + y1d**2 + y2d**2) + g * (y1 + y2)
    W = sp.eye(4)
    omega = sp.BlockMatrix([[sp.zeros(4), W], [-W, sp.zeros(4)]]).as_explicit()
    xi = sp.Matrix([x1d, x2d, y1d, y2d, 0, 0, -g, -g])

    h1 = _half * (X**2 + Y**2 - l**2)
    phi1 = X * U + Y * V                      # complete lift of h1
    phi2 = X * Sy - Y * Sx
    phi1_printed = (x2 - x1) * (x2d - x1d) - (y2 - y1) * (y1d - y2d)
    mu = sp.Matrix([[-X, X, -Y, Y], [-Y, -Y, X, X]])
    Z = sp.Matrix([
        [0, 0, 0, 0, X, -X, Y, -Y],
        [0, 0, 0, 0, Y, Y, -X, -X],
    ])
    C = sp.Matrix([[-2 * rho, 0], [0, -2 * rho]])
    C_on_M1 = sp.Matrix([[-2 * l**2, 0], [0, -2 * l**2]])

    xi_phi = sp.Matrix([U**2 + V**2, 2 * (x2d * y1d - x1d * y2d) - 2 * g * X])
    lam_TQ = sp.Matrix([(U**2 + V**2) / (2 * rho),
                        (x2d * y1d - x1d * y2d - g * X) / rho])
    lam = sp.Matrix([(U**2 + V**2) / (2 * l**2),
                     (x2d * y1d - x1d * y2d - g * X) / l**2])

    def field(l1, l2):
        # xi_L + l1 Z_1 + l2 Z_2, written out component by component
        return sp.Matrix([
            x1d, x2d, y1d, y2d,
            l1 * X + l2 * Y,
            -l1 * X + l2 * Y,
            -g + l1 * Y - l2 * X,
            -g - l1 * Y - l2 * X,
        ])

    Pxi = field(lam[0], lam[1])
    Pxi_TQ = field(lam_TQ[0], lam_TQ[1])

    # dphi_i rows in the (q, v) basis, by hand
    dphi1 = sp.Matrix([[-U, U, -V, V, -X, X, -Y, Y]])
    dphi2 = sp.Matrix([[-Sy, Sy, Sx, -Sx, -Y, -Y, X, X]])
    # Q = C^{ij} Z_j (x) dphi_i with C^{-1} = -1/(2 l^2) Id on M1, so on M1
    # P = Id + (Z_1^T dphi_1 + Z_2^T dphi_2)/(2 l^2); written out, with the diagonal
    # 1 - (X^2 + Y^2)/(2 l^2) reduced to 1/2 using X^2 + Y^2 = l^2:
    P_low = sp.Matrix([
        [-X*U - Y*Sy, X*U + Y*Sy, -X*V + Y*Sx, X*V - Y*Sx, l**2, X**2 - Y**2, 0, 2*X*Y],
        [X*U - Y*Sy, -X*U + Y*Sy, X*V + Y*Sx, -X*V - Y*Sx, X**2 - Y**2, l**2, 2*X*Y, 0],
        [-Y*U + X*Sy, Y*U - X*Sy, -Y*V - X*Sx, Y*V + X*Sx, 0, 2*X*Y, l**2, Y**2 - X**2],
        [Y*U + X*Sy, -Y*U - X*Sy, Y*V - X*Sx, -Y*V + X*Sx, 2*X*Y, 0, Y**2 - X**2, l**2],
    ]) / (2 * l**2)
    P_on_M1 = sp.Matrix.vstack(sp.Matrix.hstack(sp.eye(4), sp.zeros(4)), P_low)
    P_TQ = sp.eye(8) + (Z[0, :].T * dphi1 + Z[1, :].T * dphi2) / (2 * rho)

    printed_Pxi = sp.Matrix([
        x1d, x2d, y1d, y2d,
        -g / l**2 * X * Y,
        -g / l**2 * X * Y,
        -(g / 2 - g / l**2 * (2 * X**2 - l**2)),
        -(g / 2 - g / l**2 * (2 * X**2 - l**2)),
    ])
    return {
        "coordinates": q,
        "velocities": v,
        "parameters": [g, l],
        "lagrangian": L,
        "energy": E,
        "W": W,
        "omega": omega,
        "xi": xi,
        "h1": h1,
        "phi": [phi1, phi2],
        "phi1_printed": phi1_printed,
        "dphi": sp.Matrix.vstack(dphi1, dphi2),
        "mu": mu,
        "Z": Z,
        "C": C,
        "C_on_M1": C_on_M1,
        "xi_phi": xi_phi,
        "multipliers": lam,
        "multipliers_TQ": lam_TQ,
        "projected_field": Pxi,
        "projected_field_TQ": Pxi_TQ,
        "P_on_M1": P_on_M1,
        "P_TQ": P_TQ,
        "printed_projected_field": printed_Pxi,
    }


# ---------------------------------------------------------------------------
# Example 5.1: constants of the motion of the rolling disk
# ---------------------------------------------------------------------------

def example_5_1():
    """Example 5.1: Noether constants f1 = m xd, f2 = m yd, f3 = I1 t1d, f4 = I2 t2d.

    Z_i(f) read off from example_2_1 Z (vertical fields): Z_1(f1) = -1, Z_2(f2) = -1,
    Z_i(f3) = 0, Z_1(f4) = R c, Z_2(f4) = R s.  Lambda = P(xi_L) with accelerations
    (-R s t1d t2d, R c t1d t2d, 0, 0), so Lambda(f) = f's velocity derivative times the
    acceleration:  Lambda f1 = -m R s t1d t2d, Lambda f2 = m R c t1d t2d,
    Lambda f3 = 0, Lambda f4 = 0.  So f3 is conserved (as the paper says, via Z_i f3 = 0)
    and f4 = I2 t2d is conserved too although Z_i(f4) != 0 (the criterion is only
    sufficient); f1, f2 are not conserved on M1.  E_L is conserved on M1.
    """
    d = example_2_1()
    x, y, th1, th2 = d["coordinates"]
    xd, yd, t1d, t2d = d["velocities"]
    m, I1, I2, R = d["parameters"]
    c, s = sp.cos(th1), sp.sin(th1)
    f = {"f1": m * xd, "f2": m * yd, "f3": I1 * t1d, "f4": I2 * t2d}
    Zf = {
        "f1": (-1, 0),
        "f2": (0, -1),
        "f3": (0, 0),
        "f4": (R * c, R * s),
    }
    Lf = {
        "f1": -m * R * s * t1d * t2d,
        "f2": m * R * c * t1d * t2d,
        "f3": sp.Integer(0),
        "f4": sp.Integer(0),
    }
    return {
        "constants": f,
        "Z_of_constants": {k: tuple(sp.sympify(e) for e in val) for k, val in Zf.items()},
        "Lambda_of_constants": Lf,
        "conserved_on_M1": {"f1": False, "f2": False, "f3": True, "f4": True},
        "energy_conserved_on_M1": True,
    }
