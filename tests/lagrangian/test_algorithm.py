"""The constraint algorithm (paper §3) for any number of constraints.

Every expected value is derived by hand in the test's docstring (or taken from
``paper_reference.py``, written by hand without nhham). Conventions (DESIGN.md §2):
W = d2L/dv dv, Z_i = -W^{-1} mu_i d/dv, tangency 0 = xi_L(chi) + lambda^i Z_i(chi),
so a single multiplier is lambda = -xi_L(chi)/Z(chi).

Points of the final constraint manifolds are written by hand (substitutions), never
produced by the library's own reduction.
"""

import numpy as np
import pytest
import sympy as sp

from nhham.lagrangian.engine import Policy
from nhham import System
from nhham.render.trace import analysis_text
from nhham.lagrangian.algorithm import run_algorithm
from nhham.lagrangian.analysis import ConstraintAnalysis, analyze_constraints
from nhham.errors import RedundantConstraintError
from nhham.lagrangian.submanifold import Submanifold

import handmade
import paper_reference as ref
from handmade import same_vector, two_blocks, zero

q1, q2, q3, q4 = sp.symbols("q1 q2 q3 q4")
v1, v2, v3, v4 = sp.symbols("q1_dot q2_dot q3_dot q4_dot")
l1, l2, l3 = sp.symbols("lambda_1 lambda_2 lambda_3")
LOR = (v1**2 + v2**2 - v3**2) / 2  # the paper's Lorentzian kinetic energy


def vanish_at(exprs, sub):
    """Every expression vanishes under the hand-written substitution."""
    return all(zero(sp.sympify(e).subs(sub)) for e in exprs)


# ------------------------------------------------------------------ systems
def ex31():
    return System(["q1", "q2", "q3"], LOR, [v2 + v3], name="Example 3.1")


def ex32():
    return handmade.example_3_2()


def five_stage():
    """L = LOR + q1 q2, phi = v2 + v3.  xi^1 = q2, xi^2 = q1, xi^3 = 0 (W = diag(1,1,-1)),
    Z = -W^{-1}(0,1,1) = -d/dv2 + d/dv3, so Z(phi) = 0 and Z kills every function of
    (q, v1).  xi(phi) = q1 -> psi1 = q1; xi(q1) = v1 -> psi2 = v1; xi(v1) = q2 -> psi3 = q2;
    xi(q2) = v2 -> psi4 = v2 (on M_4 it reads -v3); Z(v2) = -1 != 0 -> stop.
    lambda = -xi(v2)/Z(v2) = q1 (= 0 on M_5).  M_5 = {q1 = q2 = v1 = v2 = v3 = 0}: dim 1."""
    return System(["q1", "q2", "q3"], LOR + q1 * q2, [v2 + v3], name="five stages")


def inconsistent_secondary():
    """L = LOR + q1 q2, phi1 = v1 + v3, phi2 = v2 - 1.  Z1 = -W^{-1}(1,0,1) = -d/dv1 + d/dv3,
    Z2 = -W^{-1}(0,1,0) = -d/dv2.  A = (Z_i(phi_j)) = [[0, 0], [0, -1]] (rank 1),
    b = (xi(phi1), xi(phi2)) = (xi^1 + xi^3, xi^2) = (q2, q1).  Row phi1 has no lambda:
    psi = q2 (stage 1).  Stage 2: Z(q2) = 0, xi(q2) = v2 = 1 on M_2: 0 = 1."""
    return System(["q1", "q2", "q3"], LOR + q1 * q2, [v1 + v3, v2 - 1], name="inconsistent")


def free_multiplier():
    """L = LOR + v4^2/2 - q4, phi1 = v2 + v3, phi2 = v4.  W = diag(1,1,-1,1);
    Z1 = -d/dv2 + d/dv3, Z2 = -d/dv4; C = [[0, 0], [0, -1]] (rank 1).
    xi = (v, 0, 0, 0, -1): xi(phi1) = 0, xi(phi2) = -1.  Tangency: 0 = 0 + 0 (phi1),
    0 = -1 - lambda2 (phi2) -> lambda2 = -1, lambda1 free.
    Dynamics xi + lambda1 Z1 - Z2 = (v, 0, -lambda1, lambda1, 0)."""
    return System(["q1", "q2", "q3", "q4"], LOR + v4**2 / 2 - q4, [v2 + v3, v4],
                  name="free multiplier")


def dimension_zero():
    """L = (v1^2 - v2^2)/2 + (q1^2 + q2^2)/2, holonomic g = q1 - q2 (lift v1 - v2).
    W = diag(1, -1); xi^1 = q1, xi^2 = -q2; Z = -W^{-1}(1, -1) = -d/dv1 - d/dv2, Z(g^c) = 0.
    xi(g^c) = q1 + q2 -> psi1 = q1 + q2; xi(psi1) = v1 + v2 -> psi2; Z(psi2) = -2 != 0.
    M_3 = {q1 = q2 = 0, v1 = v2 = 0}: a point, so the problem is inconsistent."""
    return System(["q1", "q2"], (v1**2 - v2**2) / 2 + (q1**2 + q2**2) / 2,
                  holonomic=[q1 - q2], name="dimension zero")


def no_zeros():
    """L = LOR + q2 + q2^3/3, phi = v2 + v3: Z(phi) = 0, xi(phi) = xi^2 + xi^3 = 1 + q2^2 > 0."""
    return System(["q1", "q2", "q3"], LOR + q2 + q2**3 / 3, [v2 + v3], name="no zeros")


def walk_regular():
    """Z(phi) != 0: lambda = -{phi, E}/Z(phi).  L = |v|^2/2 + q1, phi = v1 + v2:
    Z = -(d/dv1 + d/dv2), Z(phi) = -2, xi(phi) = xi^1 + xi^2 = 1 -> lambda = 1/2,
    accelerations (1 - 1/2, -1/2, 0)."""
    return System(["q1", "q2", "q3"], (v1**2 + v2**2 + v3**2) / 2 + q1, [v1 + v2])


def walk_determined_on_M2():
    """Z(phi) = 0, psi = {phi, E} != 0 on M_1, Z(psi) != 0: lambda = -{psi, E}/Z(psi) on M_2.
    L = LOR - q2^2/2, phi = v2 + v3 + q2: xi^2 = -q2, Z = -d/dv2 + d/dv3, Z(phi) = 0,
    psi = xi(phi) = v2 + xi^2 + xi^3 = v2 - q2, Z(psi) = -1, xi(psi) = xi^2 - v2 = -q2 - v2,
    lambda = -(-q2 - v2)/(-1) = -q2 - v2.  M_2: v2 = q2, v3 = -2 q2 (dim 4)."""
    return System(["q1", "q2", "q3"], LOR - q2**2 / 2, [v2 + v3 + q2])


def walk_undetermined_on_M2():
    """Z(psi) = 0 and {psi, E} = 0 on M_2: lambda arbitrary.  L = LOR + (q1^2 - q3^2)/2,
    phi = v1 + v3: xi^1 = q1, xi^3 = W^{33} dL/dq3 = q3; psi = q1 + q3; xi(psi) = phi."""
    return System(["q1", "q2", "q3"], LOR + (q1**2 - q3**2) / 2, [v1 + v3])


def rank_drop():
    """W = diag(1, -1, 1), phi = q1 v1 + v2: C = Z(phi) = -(q1^2 - 1), zero at q1 = +-1,
    so the rank of C is 1 generically and 0 on {q1^2 = 1}.  xi(phi) = v1^2, so
    lambda = -v1^2/(1 - q1^2)."""
    return System(["q1", "q2", "q3"], (v1**2 - v2**2 + v3**2) / 2, [q1 * v1 + v2])


def rolling_disk(third=None, drop=False, values=True):
    x, y, th, ph = sp.symbols("x y theta phi")
    xd, yd, thd, phd = sp.symbols("x_dot y_dot theta_dot phi_dot")
    m, I1, I2, R = sp.symbols("m I1 I2 R")
    cons = [xd - R * sp.cos(th) * phd, yd - R * sp.sin(th) * phd]
    if third is not None:
        cons.append(third)
    params = {"m": 1.3, "I1": 0.5, "I2": 0.25, "R": 0.7} if values else ["m", "I1", "I2", "R"]
    return System(["x", "y", "theta", "phi"],
                  m * (xd**2 + yd**2) / 2 + I1 * thd**2 / 2 + I2 * phd**2 / 2, cons,
                  parameters=params, name="rolling disk", drop_redundant=drop)


def rod():
    """Paper Example 4.1 (order x1, x2, y1, y2 as in paper_reference)."""
    x1, x2, y1, y2 = sp.symbols("x1 x2 y1 y2")
    x1d, x2d, y1d, y2d = sp.symbols("x1_dot x2_dot y1_dot y2_dot")
    g, l = sp.symbols("g l")
    L = (x1d**2 + x2d**2 + y1d**2 + y2d**2) / 2 - g * (y1 + y2)
    phi2 = (x2 - x1) * (y2d + y1d) - (x2d + x1d) * (y2 - y1)
    h1 = ((x2 - x1)**2 + (y2 - y1)**2 - l**2) / 2
    return System(["x1", "x2", "y1", "y2"], L, [phi2], holonomic=[h1],
                  parameters={"g": 9.81, "l": 1.5}, name="rod")


# ============================================================ paper examples
def test_example_3_1_fully_undetermined():
    """paper_reference.example_3_1: one stage, C = 0, xi(phi) = 0, lambda free."""
    r = ref.example_3_1()
    a = analyze_constraints(ex31())
    assert isinstance(a, ConstraintAnalysis)
    assert a.status == r["classification"] == "underdetermined"
    assert len(a.stages) == 1 and a.stages[0].new_constraints == ()
    assert a.stages[0].rank == 0 and a.rank_C == 0 and not a.regular
    assert a.free_multipliers == r["free_multipliers"] == 1
    assert a.free_multiplier_symbols == (l1,)
    assert dict(a.multipliers) == {}
    assert same_vector(a.dynamics, r["dynamics_family"](l1))
    assert list(a.final_constraints) == r["final_constraints"]
    assert a.inconsistency is None and a.warnings == ()


def test_example_3_2_three_stages():
    """paper_reference.example_3_2: phi -> psi = q1 -> psi' = v1, Z(psi') = -1, lambda = q1."""
    r = ref.example_3_2()
    a = analyze_constraints(ex32())
    assert a.status == r["classification"] == "determined"
    assert [st.index for st in a.stages] == [1, 2, 3]
    # Stage k's new constraints are the paper's stage k+1 constraints.
    assert list(a.stages[0].constraints) == r["stages"][0]
    assert [list(st.new_constraints) for st in a.stages[:2]] == r["stages"][1:]
    assert a.stages[2].new_constraints == ()
    # Z(chi) = (0, 0, -1) for (phi, psi, psi'): ranks 0, 0, 1.
    assert [st.rank for st in a.stages] == [0, 0, 1]
    assert [st.augmented_rank for st in a.stages] == [1, 1, 1]
    assert a.multipliers == {l1: q1}
    assert same_vector(a.dynamics, r["projected_field"])
    # M_f = M_3 = {q1 = v1 = v3 = 0}: the final constraints vanish there, dim 6 - 3.
    assert vanish_at(a.final_constraints, r["M3_substitution"])
    assert a.dimension == 3
    assert same_vector(a.dynamics.subs(r["M3_substitution"]), r["projected_field_on_M3"])


def test_example_3_2_provenance_graph():
    a = analyze_constraints(ex32())
    G = a.provenance
    assert set(G.nodes) == {"constraints[0]", "secondary[0]", "secondary[1]"}
    assert G.nodes["secondary[0]"]["expr"] == q1 and G.nodes["secondary[0]"]["stage"] == 2
    assert G.nodes["secondary[1]"]["expr"] == v1 and G.nodes["secondary[1]"]["stage"] == 3
    assert G.nodes["constraints[0]"]["kind"] == "primary"
    assert set(G.edges) == {("constraints[0]", "secondary[0]"), ("secondary[0]", "secondary[1]")}
    assert G.edges["constraints[0]", "secondary[0]"]["stage"] == 1
    assert G.edges["secondary[0]", "secondary[1]"]["stage"] == 2


def test_example_2_1_regular_rolling_disk():
    """paper_reference.example_2_1: C regular; lambda = m R th' ph' (s, -c); P as in the
    reference, compared numerically at hand-built points of M_1."""
    r = ref.example_2_1()
    a = analyze_constraints(rolling_disk(values=False))
    assert a.status == "determined" and a.regular and a.rank_C == 2
    assert len(a.stages) == 1
    x, y, th, ph = sp.symbols("x y theta phi")
    xd, yd, thd, phd = sp.symbols("x_dot y_dot theta_dot phi_dot")
    th1, th2 = r["coordinates"][2], r["coordinates"][3]
    rename = {th: th1, ph: th2, thd: sp.Symbol("theta1_dot"), phd: sp.Symbol("theta2_dot")}
    lam = sp.Matrix([a.multipliers[l1], a.multipliers[l2]]).xreplace(rename)
    assert same_vector(lam, r["multipliers"])
    assert same_vector(a.dynamics.xreplace(rename), r["projected_field"])
    P = a.projector_P.xreplace(rename)
    rng = np.random.default_rng(3)
    for _ in range(3):
        pt = {s: rng.normal() for s in r["coordinates"] + r["velocities"]}
        pt.update(zip(r["parameters"], [1.3, 0.5, 0.25, 0.7]))
        pt.update({k: v.subs(pt) for k, v in r["M1_substitution"].items()})
        diff = np.array((P - r["P"]).subs(pt).evalf(), dtype=float)
        assert np.max(np.abs(diff)) < 1e-10


def test_example_4_1_holonomic_and_nonholonomic():
    """paper_reference.example_4_1: M_1 = {h1 = 0, h1^c = 0, phi2 = 0}; C = -2 rho Id is
    regular; lambda = xi(phi)/(2 rho) on TQ (the printed P(xi_L) is wrong, see errata)."""
    r = ref.example_4_1()
    a = analyze_constraints(rod())
    assert a.status == "determined" and a.regular and a.rank_C == 2
    assert a.stages[0].labels == ("holonomic[0]", "holonomic[0].lift", "constraints[0]")
    g, l = sp.symbols("g l")
    lam = sp.Matrix([a.multipliers[l1], a.multipliers[l2]])
    assert all(sp.cancel(x - y) == 0 for x, y in zip(lam, r["multipliers_TQ"]))
    assert all(sp.cancel(x - y) == 0 for x, y in zip(a.dynamics, r["projected_field_TQ"]))
    assert a.dimension == 5  # 8 - (h1, h1^c, phi2)
    assert ("holonomic[0]", "holonomic[0].lift") in a.provenance.edges


# =========================================== the paper's one-constraint walk-through
def test_walkthrough_regular_single_constraint():
    """See walk_regular."""
    a = analyze_constraints(walk_regular())
    assert a.status == "determined" and len(a.stages) == 1 and a.rank_C == 1
    assert a.multipliers == {l1: sp.Rational(1, 2)}
    assert same_vector(a.dynamics, [v1, v2, v3, sp.Rational(1, 2), -sp.Rational(1, 2), 0])


def test_walkthrough_secondary_with_determined_multiplier():
    """See walk_determined_on_M2."""
    a = analyze_constraints(walk_determined_on_M2())
    assert a.status == "determined" and len(a.stages) == 2
    assert [list(st.new_constraints) for st in a.stages] == [[v2 - q2], []]
    assert a.multipliers == {l1: -q2 - v2}
    assert vanish_at(a.final_constraints, {v2: q2, v3: -2 * q2})
    assert a.dimension == 4


def test_walkthrough_secondary_fully_undetermined():
    """See walk_undetermined_on_M2."""
    a = analyze_constraints(walk_undetermined_on_M2())
    assert a.status == "underdetermined" and len(a.stages) == 2
    assert list(a.stages[0].new_constraints) == [q1 + q3]
    assert a.free_multiplier_symbols == (l1,) and dict(a.multipliers) == {}
    xi = sp.Matrix([v1, v2, v3, q1, 0, q3])
    Z = sp.Matrix([0, 0, 0, -1, 0, 1])
    assert same_vector(a.dynamics, xi + l1 * Z)


def test_walkthrough_iterates_until_stable():
    """The 'one then iterates' case with five stages (see five_stage's docstring)."""
    a = analyze_constraints(five_stage())
    assert a.status == "determined"
    assert [list(st.new_constraints) for st in a.stages] == [[q1], [v1], [q2], [v2], []]
    assert [st.rank for st in a.stages] == [0, 0, 0, 0, 1]
    assert a.multipliers == {l1: q1}
    assert vanish_at(a.final_constraints, {q1: 0, q2: 0, v1: 0, v2: 0, v3: 0})
    assert a.dimension == 1
    # The provenance is a chain, one edge per stage.
    chain = ["constraints[0]"] + [f"secondary[{i}]" for i in range(4)]
    for k, (u, w) in enumerate(zip(chain, chain[1:]), start=1):
        assert a.provenance.edges[u, w]["stage"] == k


# ======================================================= constructed cases
def test_singular_case_secondary_leads_to_inconsistency():
    a = analyze_constraints(inconsistent_secondary())
    assert a.status == "inconsistent"
    assert a.rank_C == 1 and not a.regular
    assert [st.rank for st in a.stages] == [1, 1]
    assert list(a.stages[0].new_constraints) == [q2]
    assert a.stages[0].block == (("constraints[1]",), (l2,))
    assert a.inconsistency.startswith("stage 2")
    assert "nonzero constant 1" in a.inconsistency
    assert a.dynamics is None and a.projector_P is None
    assert "INCONSISTENT" in analysis_text(a)


def test_condition_without_zeros_is_inconsistent():
    a = analyze_constraints(no_zeros())
    assert a.status == "inconsistent"
    assert "stage 1" in a.inconsistency and "never vanishes" in a.inconsistency


def test_consistent_singular_case_with_free_multiplier():
    a = analyze_constraints(free_multiplier())
    assert a.status == "underdetermined" and a.rank_C == 1
    assert a.free_multipliers == 1 and a.free_multiplier_symbols == (l1,)
    assert a.multipliers == {l2: -1}
    assert same_vector(a.dynamics, [v1, v2, v3, v4, 0, -l1, l1, 0])


def test_projector_on_final_manifold_for_every_solution():
    """Paper §3 end: P(X) solves the problem for every X = xi + a Z1 + b Z2.  For the
    free-multiplier case P keeps a Z1 (free) and replaces b by the determined -1:
    Q = Z2 (x) dphi2 / C22 with C22 = -1, so Q(X) = -(dphi2 . X) Z2 = -(-1 - b) Z2."""
    a = analyze_constraints(free_multiplier())
    A, B = sp.symbols("A B")
    xi = sp.Matrix([v1, v2, v3, v4, 0, 0, 0, -1])
    Z1 = sp.Matrix([0, 0, 0, 0, 0, -1, 1, 0])
    Z2 = sp.Matrix([0, 0, 0, 0, 0, 0, 0, -1])
    assert same_vector(a.project(xi + A * Z1 + B * Z2), xi + A * Z1 - Z2)
    P = a.projector_P
    assert (P * P - P).applyfunc(sp.simplify) == sp.zeros(8, 8)


def test_dimension_zero_is_inconsistent():
    a = analyze_constraints(dimension_zero())
    assert a.status == "inconsistent"
    assert [list(st.new_constraints) for st in a.stages] == [[q1 + q2], [v1 + v2], []]
    assert "stage 3" in a.inconsistency and "dimension 0" in a.inconsistency
    assert a.dimension == 0


def test_redundant_rolling_disk_reported_and_dropped():
    """phi3 = cos(th) phi1 + sin(th) phi2 (written with R (cos^2 + sin^2) th2'): its
    one-form is the same combination, so it is redundant.  Without permission System
    names the combination; with it, phi3 is dropped and the dynamics is the disk's."""
    x, y, th, ph = sp.symbols("x y theta phi")
    xd, yd, thd, phd = sp.symbols("x_dot y_dot theta_dot phi_dot")
    R = sp.Symbol("R")
    c, s = sp.cos(th), sp.sin(th)
    third = c * xd + s * yd - R * (c**2 + s**2) * phd
    with pytest.raises(RedundantConstraintError) as info:
        rolling_disk(third)
    assert "constraints[2]" in str(info.value) and "cos(theta)" in str(info.value)
    a = analyze_constraints(rolling_disk(third, drop=True))
    assert [d.label for d in a.dropped] == ["constraints[2]"]
    assert a.dropped[0].combination == {"constraints[0]": c, "constraints[1]": s}
    assert "dropped redundant constraints: constraints[2]" in analysis_text(a)
    m = sp.Symbol("m")
    assert a.status == "determined" and a.regular
    assert same_vector([a.multipliers[l1], a.multipliers[l2]],
                       [m * R * thd * phd * s, -m * R * thd * phd * c])
    plain = analyze_constraints(rolling_disk())
    assert same_vector(a.dynamics, plain.dynamics)
    assert a.final_constraints == plain.final_constraints


# =============================================================== idempotence
def test_idempotent_on_final_constraints_generic_loop():
    """Feeding M_f's constraints back as primary ones gives one stage, nothing new, the
    same M_f and the same multiplier."""
    a = analyze_constraints(ex32(), decompose=False)
    run = a.blocks[0].run
    system = ex32()
    again = run_algorithm(run.base_field, run.vertical_fields, run.final_constraints,
                          run.final_labels, lambda eqs: Submanifold(system, eqs),
                          variables=system.state)
    assert len(again.stages) == 1 and again.stages[0].new_constraints == ()
    assert again.final_constraints == run.final_constraints
    assert again.multipliers == {l1: q1} and again.status == "determined"


def test_idempotent_as_a_system():
    """Example 3.2's M_3 as a system: holonomic q1 (lift v1), affine v1 + v3 and v1
    (redundant with the lift, dropped).  One stage; M_1 = M_3 = {q1 = v1 = v3 = 0}."""
    s = System(["q1", "q2", "q3"], LOR + q1**2 / 2, [v1 + v3, v1], holonomic=[q1],
               drop_redundant=True)
    a = analyze_constraints(s)
    assert [d.label for d in a.dropped] == ["constraints[1]"]
    assert len(a.stages) == 1 and a.stages[0].new_constraints == ()
    assert vanish_at(a.final_constraints, {q1: 0, v1: 0, v3: 0})
    assert a.dimension == 3 and a.status == "determined"


# ============================================== generic loop on T*Q (Hamiltonian)
def test_generic_loop_with_hamiltonian_ingredients():
    """Example 3.2 on T*Q: p = W v gives p1 = v1, p2 = v2, p3 = -v3,
    H = (p1^2 + p2^2 - p3^2)/2 - q1^2/2, X_H = (dH/dp, -dH/dq) = (p1, p2, -p3, q1, 0, 0),
    phi^H = p1 - p3, Z^H = -mu_A d/dp_A = -d/dp1 - d/dp3.  Same chain: q1, then p1
    (Z^H(p1) = -1), lambda = -X_H(p1)/Z^H(p1) = q1."""
    p1, p2, p3 = sp.symbols("p_q1 p_q2 p_q3")
    system = ex32()
    XH = sp.Matrix([p1, p2, -p3, q1, 0, 0])
    ZH = sp.Matrix([[0, 0, 0, -1, 0, -1]])
    run = run_algorithm(XH, ZH, [p1 - p3], ["constraints[0]"],
                        lambda eqs: Submanifold(system, eqs, fibre=(p1, p2, p3)))
    assert run.variables == (q1, q2, q3, p1, p2, p3)
    assert [list(st.new_constraints) for st in run.stages] == [[q1], [p1], []]
    assert run.status == "determined" and run.multipliers == {l1: q1}
    assert same_vector(run.dynamics, [p1, p2, -p3, 0, 0, -q1])
    assert run.dimension == 3


def test_stage_bound_is_reported():
    a = analyze_constraints(five_stage(), max_stages=2)
    assert not a.converged and len(a.stages) == 2
    assert any("stage bound 2 hit" in w for w in a.warnings)
    assert "NOT CONVERGED" in analysis_text(a)


# ============================================= sampled versus exact decisions
SYSTEMS = [ex31, ex32, five_stage, inconsistent_secondary, no_zeros, free_multiplier,
           dimension_zero, walk_regular, walk_determined_on_M2, walk_undetermined_on_M2,
           rank_drop, rolling_disk, rod, two_blocks]


def _signature(a):
    return (a.status, [st.rank for st in a.stages], [len(st.new_constraints) for st in a.stages],
            a.dimension, a.free_multipliers, a.rank_C)


@pytest.mark.parametrize("make", SYSTEMS, ids=lambda f: f.__name__)
@pytest.mark.parametrize("precision", [None, 30], ids=["float64", "mp30"])
def test_sampled_decisions_agree_with_exact(make, precision):
    system = make()
    exact = analyze_constraints(system)
    sampled = analyze_constraints(system, policy=Policy(exact=False, precision=precision))
    assert _signature(sampled) == _signature(exact)
    assert len(sampled.warnings) == len(exact.warnings)  # only rank_drop warns, both ways
    # Every rank and vanishing decision was sampled (the choice of a regular block
    # of a constant matrix needs no samples and is not a decision on M_k).
    decisions = [e.decision for st in sampled.stages for e in st.decisions
                 if "block" not in e.subject]
    assert decisions and all(d.method == "sampled" for d in decisions)
    assert {d.precision for d in decisions} == {"float64" if precision is None else "mpmath:30"}
    for s in exact.multipliers:
        assert sp.cancel(exact.multipliers[s] - sampled.multipliers[s]) == 0


def test_near_singular_case_warns_in_float64():
    """phi1 = v1, phi2 = v1 + eps v2 with eps = 1/150000 and W = Id: C = -[[1, 1],
    [1, 1 + eps^2]], det C = eps^2 != 0 (exactly regular: lambda = 0 for free motion).
    Its singular values are about 2 and eps^2/2, ratio ~1.1e-11: between float64's zero
    level (1e-12) and its tolerance (1e-9), so float64 sampling would call it singular; it
    must say that it is doubtful.  30 digits see the true rank without a warning."""
    eps = sp.Rational(1, 150000)
    s = System(["q1", "q2", "q3"], (v1**2 + v2**2 + v3**2) / 2, [v1, v1 + eps * v2])
    exact = analyze_constraints(s)
    assert exact.regular and exact.status == "determined" and exact.warnings == ()
    f64 = analyze_constraints(s, policy=Policy(exact=False))
    assert f64.rank_C == 1  # the float64 answer differs from the exact one ...
    assert any("near-singular" in w for w in f64.warnings)  # ... and says it is doubtful
    assert "WARNING" in analysis_text(f64)
    mp = analyze_constraints(s, policy=Policy(exact=False, precision=30))
    assert mp.regular and mp.status == "determined" and mp.warnings == ()


def test_rank_drop_on_M1_is_warned_with_location():
    """See rank_drop."""
    s = rank_drop()
    a = analyze_constraints(s)
    assert a.status == "determined" and a.rank_C == 1
    assert zero(a.multipliers[l1] + v1**2 / (1 - q1**2))
    drops = [w for w in a.warnings if "not constant" in w]
    assert drops and "drops from 1 to 0" in drops[0] and "q1=" in drops[0]
    hit = float(drops[0].split("q1=")[1].split(",")[0])
    assert abs(abs(hit) - 1) < 1e-8
