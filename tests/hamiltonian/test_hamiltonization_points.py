"""Chaplygin's multiplier in velocity coordinates and at exact points
(nhham.hamiltonian.hamiltonization_points) against independent routes.

- theta found in (r, r') and carried to (r, p) against theta solved directly in (r, p)
  with the inverse Legendre map (the route nhham took before), on the particle and the
  sleigh;
- the values at an exact point against the hand formulas evaluated at that point;
- the Chaplygin sphere (marble) on T*SO(3) and the 3-D rolling disc, from reduced data
  formed here from the definitions (L_c = L(r, r', -A r'), J = dL/ds', B^a = dA^a), so that
  the test does not pay for the reduction's 30-digit check against P(xi_L).
"""

import functools
import itertools

import sympy as sp

from nhham import System, models
from nhham.hamiltonian.hamiltonization import hamiltonize
from nhham.hamiltonian.hamiltonization_points import decide_at_a_point, velocity_equations
from nhham.journeys.answer import as_scene
from nhham.lagrangian.chaplygin import ChaplyginReduction, chaplygin_reduction
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.domains import evaluate
from nhham.system.naming import momentum_symbol

L3 = "(x_dot**2 + y_dot**2 + z_dot**2)/2"


@functools.lru_cache(maxsize=1)
def sleigh():
    return chaplygin_reduction(models.chaplygin_sleigh(), symmetry=["y"])


@functools.lru_cache(maxsize=1)
def sleigh_hamiltonized():
    return hamiltonize(sleigh())


def theta_in_momenta(red):
    """theta ^ Omega_nh = -d Omega_nh solved in (r, p): r' = W^{-1} p, Omega_nh =
    [[-G(r, p), 1], [-1, 0]] (the definition in the module docstring), sympy's linsolve."""
    r, v = list(red.shape), list(red.shape_velocities)
    k = len(r)
    p = [momentum_symbol(x) for x in r]
    W = sp.Matrix(k, k, lambda i, j: sp.diff(red.lagrangian, v[i], v[j]))
    to_p = dict(zip(v, W.LUsolve(sp.Matrix(p))))
    Omega = sp.zeros(2 * k, 2 * k)
    for a in range(k):
        Omega[a, k + a], Omega[k + a, a] = 1, -1
        for c in range(k):
            Omega[a, c] = -red.gyroscopic_form[a, c].xreplace(to_p)
    z, t = r + p, sp.symbols(f"t0:{2 * k}")
    eqs = [t[i] * Omega[j, l] + t[j] * Omega[l, i] + t[l] * Omega[i, j]
           + sp.diff(Omega[j, l], z[i]) + sp.diff(Omega[l, i], z[j]) + sp.diff(Omega[i, j], z[l])
           for i, j, l in itertools.combinations(range(2 * k), 3)]
    return next(iter(sp.linsolve([sp.cancel(e) for e in eqs], t)))


def test_theta_in_velocity_coordinates_equals_theta_in_momenta():
    """The particle and the sleigh: theta_v = Leg^* theta carried back to (r, p) is the
    solution of the equations written in (r, p)."""
    for red in (chaplygin_reduction(System(["x", "y", "z"], L3, ["z_dot - y*x_dot"])),
                sleigh()):
        found = hamiltonize(red) if red is not sleigh() else sleigh_hamiltonized()
        assert found.route == "closed form"
        expected = theta_in_momenta(red)
        assert all(sp.simplify(a - b) == 0 for a, b in zip(found.theta, expected))


def test_the_particle_at_an_exact_point_matches_the_hand_formulas():
    """z' = y x': at the point, theta = -y/(1 + y^2) dy and d theta = 0 (nothing refuted),
    and the one nonzero Jacobiator, of (x, p_x, p_y), is -y/(1 + y^2) there."""
    system = System(["x", "y", "z"], L3, ["z_dot - y*x_dot"])
    verdict = decide_at_a_point(velocity_equations(chaplygin_reduction(system)), system)
    y = next(s for s in verdict.env if str(s) == "y")
    hand, = evaluate([-y / (1 + y**2)], verdict.env)
    assert verdict.proof is None
    assert list(verdict.theta) == [0, hand, 0, 0]
    assert [x for _, x in verdict.dtheta] == [0]
    assert verdict.jacobiator == ((("x", "p_x", "p_y"), hand),)


def test_the_sleigh_at_an_exact_point_proves_theta_not_closed():
    """Shape (x, theta), symmetry y: d theta = -a m sin th/((I + m a^2) cos^2 th) dx^dth
    (tests/hamiltonian/test_hamiltonization.py), nonzero at the point: a proof."""
    red = sleigh()
    verdict = decide_at_a_point(velocity_equations(red), red.system)
    s = {str(x): x for x in verdict.env}
    a, m, I, th = s["a"], s["m"], s["I"], s["theta"]
    hand, = evaluate([-a * m * sp.sin(th) / ((I + m * a**2) * sp.cos(th)**2)], verdict.env)
    assert verdict.proof == "not closed"
    assert verdict.dtheta == (((0, 1), hand),) and hand != 0


def reduced_by_hand(scene, symmetry) -> ChaplyginReduction:
    """The reduced data from their definitions (s' = -A r' solved from the constraints,
    L_c, J_a = dL/ds'^a and B^a_ij = d_i A^a_j - d_j A^a_i), without the reduction's check."""
    system = as_scene(scene).system
    q, v = list(system.coordinates), list(system.velocities)
    sym = [c for c in q if str(c) in symmetry]
    shape = [c for c in q if c not in sym]
    sdot = [v[q.index(c)] for c in sym]
    rdot = [v[q.index(c)] for c in shape]
    solved = {w: sp.trigsimp(sp.collect(sp.expand(e), rdot))  # r (pitch' sin yaw + ...)
              for w, e in sp.solve(list(system.phi), sdot, dict=True)[0].items()}
    A = sp.Matrix([[-sp.diff(solved[w], x) for x in rdot] for w in sdot])
    k = len(shape)
    B = tuple(sp.Matrix(k, k, lambda i, j: sp.diff(A[a, j], shape[i]) - sp.diff(A[a, i], shape[j]))
              for a in range(len(sym)))
    J = sp.Matrix([sp.diff(system.lagrangian, w).xreplace(solved) for w in sdot])
    L_c = system.lagrangian.xreplace(solved)
    return ChaplyginReduction(system, tuple(shape), tuple(sym), A, L_c, J, B, sp.zeros(k, 1),
                              sp.zeros(k, 1), Decision(True, "exact", "not checked here"),
                              sp.zeros(k, 1), sp.zeros(0, k))


def test_the_chaplygin_marble_on_t_star_so3_has_no_factor():
    """The Chaplygin sphere's first stage (shape yaw, pitch, roll; T*SO(3), dimension 6):
    no conformal factor, as Ehlers, Koiller, Montgomery & Rios (2005) state for the marble.
    The equations with a dp leg already fail: they force theta's dp part to vanish and then
    theta_a W_bc - theta_b W_ac = dG_ab/dr'^c (nine equations, three unknowns) has no
    solution at an exact point where Omega_nh is nondegenerate: a proof."""
    found = hamiltonize(reduced_by_hand("examples/chaplygin_sphere.toml", ["x", "y"]))
    assert not found.hamiltonizable and found.route == "exact point"
    assert found.obstruction.startswith(
        "the equations theta ^ Omega_nh = -d Omega_nh have no solution: decided at an "
        "exact point")
    assert "already its components with a dp leg" in found.obstruction
    assert "component reads 0 = dG_(" in found.obstruction
    assert found.theta is None and found.conformal_factor is None
    assert found.jacobiator_before  # proved nonzero at the point: not Poisson
    assert found.to_dict()["decision"]["route"] == "exact point"


def test_the_rolling_disc_has_no_solution_at_an_exact_point():
    """The 3-D disc (shape yaw, lean, spin; L_c and J in examples/rolling_disc_3d.toml's
    conventions): by hand G = m R^2 cos(lean) lean' dyaw^dspin and W_lean,lean = 5 m R^2/4
    with no lean cross terms, so dG_(yaw, spin)/dp_lean = (4/5) cos(lean). With theta's dp
    part zero the dyaw^dspin^dp_lean component of the equations reads 0 = (4/5) cos(lean):
    no solution. At the exact point: the same, with the Jacobiator of
    (lean, p_yaw, p_spin) = -(4/5) cos(lean) there."""
    red = reduced_by_hand("examples/rolling_disc_3d.toml", ["x", "y"])
    verdict = decide_at_a_point(velocity_equations(red), red.system)
    lean = next(s for s in verdict.env if str(s) == "lean")
    hand, = evaluate([-sp.Rational(4, 5) * sp.cos(lean)], verdict.env)
    assert verdict.proof == "no solution" and "dp leg" in verdict.detail
    assert dict(verdict.jacobiator)[("lean", "p_yaw", "p_spin")] == hand
    assert "dyaw^dspin^dp_lean component reads 0" in verdict.detail


def test_the_route_follows_the_size_and_a_point_that_refutes_nothing_leaves_it_to_the_closed_form(
        monkeypatch):
    """With every Omega_nh counted as large: the particle's point refutes nothing, so the
    closed form finds f = (1 + y^2)^(-1/2) (route closed form); the sleigh's point proves
    d theta != 0 (route exact point, theta not given)."""
    from nhham.hamiltonian import hamiltonization

    monkeypatch.setattr(hamiltonization, "CLOSED_FORM_OPS", 0)
    particle = hamiltonize(chaplygin_reduction(System(["x", "y", "z"], L3, ["z_dot - y*x_dot"])))
    y = next(s for s in particle.conformal_factor.free_symbols if str(s) == "y")
    assert particle.route == "closed form" and particle.hamiltonizable
    assert sp.simplify(particle.conformal_factor - 1 / sp.sqrt(1 + y**2)) == 0
    found = hamiltonize(sleigh())
    assert found.route == "exact point" and not found.hamiltonizable and found.theta is None
    assert found.obstruction.startswith("theta is not closed: decided at an exact point")
    assert [t for t, _ in found.jacobiator_before] == [("x", "p_x", "p_theta"),
                                                        ("theta", "p_x", "p_theta")]


def test_the_decision_record_follows_the_schema():
    """The JSON key decision of both routes against nhham's output schema."""
    import jsonschema

    import nhham

    schema = nhham.output_schema()
    part = dict(schema["$defs"]["hamiltonize"]["properties"]["decision"], **{"$defs": schema["$defs"]})
    for found in (sleigh_hamiltonized(),
                  hamiltonize(reduced_by_hand("examples/rolling_disc_3d.toml", ["x", "y"]))):
        jsonschema.validate(found.to_dict()["decision"], part)
