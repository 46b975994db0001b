"""The cross-check where C is singular: both constraint algorithms compared through their
data at exact points of every M_k (nhham.hamiltonian.staged), against stages and ranks
known by hand, the symbolic T*Q route, and planted errors that must be caught."""

from pathlib import Path

import numpy as np
import sympy as sp

import pytest

from nhham.lagrangian.engine import Policy
from nhham import models
from nhham.hamiltonian.crosscheck import cross_check

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
CHECKS = {"stages", "legendre inverse", "field", "multipliers", "symplectic form", "Poisson map"}


def _curvilinear(name):
    import handmade

    return getattr(handmade, name)()


@pytest.mark.parametrize("make, status, ranks, free", [
    (lambda: _curvilinear("curvilinear_3_2"), "determined", [0, 0, 1], 0),
    (lambda: _curvilinear("curvilinear_five_stage"), "determined", [0, 0, 0, 0, 1], 0),
    (lambda: _curvilinear("curvilinear_free_multiplier"), "underdetermined", [1], 1),
    (models.paper_example_3_1, "underdetermined", [0], 1),
    (models.paper_example_3_2, "determined", [0, 0, 1], 0),
], ids=["curvilinear_3_2", "five_stage", "free_multiplier", "paper_3_1", "paper_3_2"])
def test_singular_C_is_checked_at_exact_points_of_every_M_k(make, status, ranks, free):
    """C singular: the T*Q data at Leg of exact points of each M_k equal the TQ data, so
    both sides have the hand-derived stages (ranks known by hand: the systems are
    changes of coordinates of hand-solved ones), and the fields agree on M_f."""
    report = cross_check(make(), method="points", policy=Policy(samples=3))
    assert report.method == "points" and report.agree, report.describe()
    assert {c.how for c in report.checks} == {"points"} and set(report.detail) == CHECKS
    assert report.statuses == (status, status)
    assert [s["rank"] for s in report.hamiltonian_stages] == ranks
    assert report.lagrangian_stages == report.hamiltonian_stages
    assert f"({free} free multiplier(s)" in report.detail["field"].detail


def test_singular_C_at_points_matches_the_symbolic_route():
    """Example 3.2 both ways: the stages found at exact points are those of the T*Q
    algorithm run symbolically (H written out)."""
    points = cross_check(models.paper_example_3_2(), method="points", policy=Policy(samples=3))
    exact = cross_check(models.paper_example_3_2(), method="exact")
    assert exact.method == "exact" and exact.agree
    assert points.hamiltonian_stages == exact.hamiltonian_stages
    assert points.statuses == exact.statuses


def test_an_inconsistent_singular_system_at_exact_points():
    """curvilinear_inconsistent (by hand: psi = q2 at stage 1, then 0 = 1 on M_2): the
    T*Q data equal the TQ data at points of M_1 and M_2, so the T*Q run is inconsistent
    too; its stages are those of the symbolic T*Q algorithm."""
    system = _curvilinear("curvilinear_inconsistent")
    report = cross_check(system, method="points", policy=Policy(samples=3))
    assert report.method == "points" and report.agree
    assert report.statuses == ("inconsistent", "inconsistent")
    assert [(s["rank"], s["augmented_rank"]) for s in report.hamiltonian_stages] == \
        [(1, 2), (1, 2)]
    assert "inconsistent on both sides" in report.detail["field"].detail
    exact = cross_check(system, method="exact")
    assert exact.hamiltonian_stages == report.hamiltonian_stages


def test_the_coupled_pair_is_compared_at_exact_points():
    """examples/curvilinear_pair.toml (n = 6, W(q) dense with sines and cosines): the
    symbolic T*Q algorithm did not finish in 300 s; at exact points of M_1, M_2, M_3 the
    two sides agree, stages 0, 0, 2 (its header, by hand)."""
    import nhham

    system = nhham.load_scene(EXAMPLES / "curvilinear_pair.toml").system
    report = cross_check(system, policy=Policy(samples=3))
    assert report.method == "points" and report.agree
    assert [s["rank"] for s in report.hamiltonian_stages] == [0, 0, 2]
    assert [s["constraints"] for s in report.hamiltonian_stages] == [2, 4, 6]


def test_a_wrong_chain_rule_is_detected_on_M_k(monkeypatch):
    """d(chi o Leg^-1)/dq = chi_q - chi_v W^-1 M with the sign of the M term flipped:
    X_H(chi^H) differs from xi_L(chi) at exact points of the M_k (the stages check)."""
    from nhham.hamiltonian.side import TransportedFunctions

    def wrong(self, backend, vals, W, M):
        val, gq, gp = original(self, backend, vals, W, M)
        return val, gq + 2 * (gp @ M), gp

    original = TransportedFunctions.gradients
    monkeypatch.setattr(TransportedFunctions, "gradients", wrong)
    report = cross_check(_curvilinear("curvilinear_3_2"), method="points", policy=Policy(samples=2))
    assert report.method == "points" and not report.detail["stages"].agree
    assert "differ from Z_i(chi), xi_L(chi)" in report.detail["stages"].detail


def test_a_wrong_vertical_field_is_detected_with_free_multipliers(monkeypatch):
    """Z^H = (0, +mu): with a free multiplier given a seeded value the fields differ;
    the multipliers (solved from Z_i^H(chi^H), which does not use the flipped field)
    still agree."""
    from nhham.hamiltonian.side import HamiltonianPoint

    monkeypatch.setattr(HamiltonianPoint, "vertical",
                        lambda self: np.concatenate([self.mu * 0, self.mu], axis=1))
    report = cross_check(_curvilinear("curvilinear_free_multiplier"), method="points",
                         policy=Policy(samples=2))
    assert not report.detail["field"].agree and report.detail["multipliers"].agree


def test_singular_C_without_exact_points_falls_back_to_the_symbolic_route():
    """A secondary constraint sin(q1) = 0 has no exact points; parameter values where
    the generic ranks fail make the points disagree with the generic algorithm. Both go
    the symbolic way, and agree."""
    import nhham

    q1 = sp.Symbol("q1")
    v1, v2, v3 = sp.symbols("q1_dot q2_dot q3_dot")
    system = nhham.System(["q1", "q2", "q3"], (v1**2 + v2**2 - v3**2) / 2 + sp.cos(q1),
                          [v1 + v3])
    report = cross_check(system, method="points", policy=Policy(samples=2))
    assert report.method == "exact" and report.agree
    null = nhham.load_scene(EXAMPLES / "parametric_null_constraint.toml").system
    report = cross_check(null, method="points", policy=Policy(samples=2))
    assert report.method == "exact" and report.agree
