"""Section 5: constants of the motion and Lie symmetries (paper Example 5.1)."""

import numpy as np
import sympy as sp

import nhham
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.lagrangian.symmetries import (
    complete_lift,
    constant_of_motion,
    cyclic_constants,
    lie_bracket,
    lie_symmetry,
)

import handmade
import paper_reference


def disk_as_in_paper():
    ref = paper_reference.example_2_1()
    system = nhham.System(ref["coordinates"], ref["lagrangian"], ref["phi"],
                          parameters=ref["parameters"])
    return system, lagrangian_geometry(system)


def test_example_5_1_cyclic_constants():
    """x, y, theta1, theta2 are cyclic. f3 = I1 theta1' passes the paper's
    sufficient test; f4 = I2 theta2' is conserved although Z_i f4 != 0; f1, f2
    are not conserved (their derivatives are -/+ m R th1' th2' sin/cos th1)."""
    system, G = disk_as_in_paper()
    ref = paper_reference.example_5_1()
    found = cyclic_constants(G)
    assert [q.name for q in found] == ["x", "y", "theta1", "theta2"]
    names = {"x": "f1", "y": "f2", "theta1": "f3", "theta2": "f4"}
    for q, test in found.items():
        key = names[q.name]
        assert sp.expand(test.function - ref["constants"][key]) == 0
        assert test.conserved.value == ref["conserved_on_M1"][key]
        assert test.sufficient.value == (ref["Z_of_constants"][key] == (0, 0))
        assert test.free_constant.value  # every f_i is a constant of xi_L
    assert found[system.coordinates[2]].conserved.method == "exact"
    assert "sufficient test" in found[system.coordinates[3]].describe()
    derivative = found[system.coordinates[0]].derivative
    assert sp.simplify(derivative - ref["Lambda_of_constants"]["f1"]) == 0


def test_energy_is_conserved_and_passes_sufficient_test():
    """Z_i(E_L) = -mu_i v = h_i - phi_i = 0 on M_1 when h = 0."""
    _, G = disk_as_in_paper()
    test = constant_of_motion(G, G.energy)
    assert test.conserved.value and test.sufficient.value


def test_affine_energy_not_conserved():
    system, _ = handmade.drifting_particle()
    G = lagrangian_geometry(system)
    assert not constant_of_motion(G, G.energy).conserved.value


def test_complete_lift_and_bracket_by_hand():
    system, _ = handmade.rolling_disk(params=False)
    x, y, th, ph, xd, yd, thd, phd = system.state
    Xc = complete_lift(system, [-y, x, 1, 0])
    assert Xc == sp.Matrix([-y, x, 1, 0, -yd, xd, 0, 0])
    # [d/dx, x d/dy] = d/dy
    state = sp.Matrix(system.state)
    A = sp.Matrix([1, 0, 0, 0, 0, 0, 0, 0])
    B = sp.Matrix([0, x, 0, 0, 0, 0, 0, 0])
    assert lie_bracket(state, A, B) == sp.Matrix([0, 1, 0, 0, 0, 0, 0, 0])


def test_lie_symmetries_of_the_rolling_disk():
    """Translations, rotations of the plane with the disk, and phi-shifts are
    symmetries; a theta-shift alone is not (its lift breaks the constraints)."""
    system, _ = handmade.rolling_disk(params=False)
    G = lagrangian_geometry(system)
    x, y = system.coordinates[:2]
    assert lie_symmetry(G, [1, 0, 0, 0])
    assert lie_symmetry(G, [0, 0, 0, 1])
    assert lie_symmetry(G, [-y, x, 1, 0])
    shift = lie_symmetry(G, [0, 0, 1, 0])
    assert not shift.tangent.value and not shift
    # A scaling of x alone is tangent to nothing useful either.
    assert not lie_symmetry(G, [x, 0, 0, 0])


def test_example_4_1_projector_on_M1_matches_reference():
    """P on M_1 = Id + (Z_1^T dphi_1 + Z_2^T dphi_2) / (2 l^2) (hand derivation)."""
    system, point = handmade.two_particle_rod()
    ref = paper_reference.example_4_1()
    G = lagrangian_geometry(system)
    rng = np.random.default_rng(3)
    for _ in range(3):
        pt = point(rng)
        assert np.allclose(handmade.evaluate_matrix(G.projector_P, pt),
                           handmade.evaluate_matrix(ref["P_on_M1"], pt), atol=1e-10)


def test_example_4_1_printed_field_is_wrong():
    """The erratum: the printed P(xi_L) is not tangent to M_1 (docs/paper-errata.md)."""
    system, point = handmade.two_particle_rod()
    ref = paper_reference.example_4_1()
    G = lagrangian_geometry(system)
    pt = point(np.random.default_rng(5))
    ours = handmade.evaluate_matrix(G.projected_field, pt)
    printed = handmade.evaluate_matrix(ref["printed_projected_field"], pt)
    assert np.allclose(ours, handmade.evaluate_matrix(ref["projected_field"], pt), atol=1e-10)
    assert not np.allclose(ours, printed, atol=1e-3)
