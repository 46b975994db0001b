"""Chetaev's rule on T*Q: Z^H = -mu(q, Leg^-1) d/dp, C^H and lambda^H for a constraint
nonlinear in v, against values worked out by hand (the isokinetic particle, p = m v)."""

import sympy as sp

import nhham
from nhham.hamiltonian.side import hamiltonian_side

m, g, c = sp.symbols("m g c", positive=True)
xd, yd = sp.symbols("x_dot y_dot")
px, py = sp.symbols("p_x p_y")


def test_isokinetic_vertical_fields_matrix_and_multiplier():
    system = nhham.System(["x", "y"], m * (xd**2 + yd**2) / 2 - m * g * sp.Symbol("y"),
                          [(xd**2 + yd**2 - c**2) / 2], parameters=[m, g, c])
    side = hamiltonian_side(system)
    # mu = v = p/m at Leg^-1: Z^H = -(p_x/m, p_y/m) d/dp; phi^H = (|p|^2/m^2 - c^2)/2
    assert list(side.vertical_fields) == [0, 0, -px / m, -py / m]
    # C^H = Z^H(phi^H) = -(p_x^2 + p_y^2)/m^3 (= C o Leg^-1 = -|v|^2/m), and
    # lambda^H = -X_H(phi^H)/C^H with X_H(phi^H) = -g p_y/m: -m^2 g p_y/|p|^2
    assert sp.simplify(side.constraint_matrix[0] + (px**2 + py**2) / m**3) == 0
    assert sp.simplify(side.multipliers[0] + m**2 * g * py / (px**2 + py**2)) == 0
    # one constraint: its bracket with itself vanishes, so it is first class
    assert nhham.classify(system).data["first_class"] == 1
