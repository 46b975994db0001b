"""The Dirac–Bergmann chain against values worked out by hand (not from nhham).

Each case is a textbook singular Lagrangian; the expected generations, classes, degrees
of freedom, gauge transformations and Dirac brackets are derived in the comments.
"""

from pathlib import Path

import pytest
import sympy as sp

from nhham import System, load_scene
from nhham.errors import InputError, ValidationError
from nhham.hamiltonian import dirac_bergmann as db_module
from nhham.hamiltonian.dirac_bergmann import dirac_bergmann
from nhham.hamiltonian.primary import legendre_image

GALLERY = Path(__file__).resolve().parents[2] / "examples" / "singular"


def chain(name, **values):
    return dirac_bergmann(load_scene(GALLERY / name, values=values or None).system)


def same_up_to_sign(found, expected):
    """Each constraint equals the expected one up to a nonzero constant factor."""
    assert len(found) == len(expected), (found, expected)
    for f, e in zip(found, expected):
        ratio = sp.cancel(sp.sympify(f) / sp.sympify(e))
        assert ratio.is_number and ratio != 0, (f, e)


S = sp.Symbol


def test_gauge_shift_by_hand():
    # L = (q1' - q2)^2/2: p1 = q1' - q2, p2 = 0. H_c = p1^2/2 + p1 q2.
    # {p2, H_c} = -p1: secondary p1 = 0; {p1, H_c} = 0. B = 0: 2 first class, dof 0.
    # Castellani: G = eps' p2 + eps p1, so delta q1 = eps, delta q2 = eps'.
    db = chain("gauge_shift.toml")
    same_up_to_sign(db.generations[0], [S("p_q2")])
    same_up_to_sign(db.generations[1], [S("p_q1")])
    assert (db.first_class, db.second_class, db.degrees_of_freedom) == (2, 0, 0)
    (g,) = db.gauge_generators
    assert dict(g.transformations) == {S("q1"): S("eps_1"), S("q2"): S("eps_1_dot")}
    assert g.checked.value


def test_christ_lee_by_hand():
    # p_xi = 0 -> {p_xi, H_c} = -dH_c/dxi = -(x1 p2 - x2 p1) (H_c has xi (x1 p2 - x2 p1)):
    # Gauss's law J = x1 p2 - x2 p1 = 0; {J, H_c} = 0 (V radial). 2 first class,
    # dof (6 - 4)/2 = 1; G = eps' p_xi + eps J turns the plane: delta x1 = -eps x2.
    db = chain("christ_lee.toml")
    x1, x2, p1, p2 = S("x1"), S("x2"), S("p_x1"), S("p_x2")
    same_up_to_sign(db.generations[1], [x1 * p2 - x2 * p1])
    assert (db.first_class, db.second_class, db.degrees_of_freedom) == (2, 0, 1)
    moves = dict(db.gauge_generators[0].transformations)
    assert moves[S("xi")] == S("eps_1_dot")
    assert sp.simplify(moves[x1] / moves[x2] + x2 / x1) == 0  # a rotation


def test_landau_level_by_hand():
    # L = B x y' - k r^2/2: p_x = 0, p_y = B x; {p_x, p_y - B x} = B: second class.
    # {x, y}_D = -1/B; the Dirac flow of H = k r^2/2: x' = -k y/B, y' = k x/B, a
    # rotation at the rate k/B. dof (4 - 2)/2 = 1.
    db = chain("landau_level.toml")  # B = 2, k = 1
    assert len(db.generations) == 1
    assert (db.first_class, db.second_class, db.degrees_of_freedom) == (0, 2, 1)
    z = db.algebra.variables
    D = db.dirac_bracket
    assert D[z.index(S("x")), z.index(S("y"))] == sp.Rational(-1, 2)
    x, y = S("x"), S("y")
    H = db.image.canonical_hamiltonian
    flow = [sum(D[i, j] * sp.diff(H, z[j]) for j in range(4)) for i in (0, 1)]
    assert sp.simplify(flow[0] + y / 2) == 0 and sp.simplify(flow[1] - x / 2) == 0


def test_proca_mode_massive_and_massless():
    # m != 0: p_A0 -> m^2 A0 - k p_Az (from {p_A0, H_c} = -dH/dA0), bracket m^2: second
    # class, dof 1. m = 0: p_A0 -> p_Az, both first class, dof 0 (at the scene's values,
    # not the generic answer).
    massive = chain("proca_mode.toml")
    assert (massive.first_class, massive.second_class, massive.degrees_of_freedom) == (0, 2, 1)
    massless = chain("proca_mode.toml", m=0.0)
    same_up_to_sign(massless.generations[1], [S("p_Az")])
    assert (massless.first_class, massless.second_class,
            massless.degrees_of_freedom) == (2, 0, 0)


def test_pendulum_with_its_multiplier_by_hand():
    # p_lam -> r^2 - 1 -> x p_x + y p_y -> lam r^2 + |p|^2 - g y (times 100): four
    # generations, all second class, dof (6 - 4)/2 = 1;
    # {x_i, p_j}_D = delta_ij - x_i x_j / r^2.
    db = chain("pendulum_multiplier.toml")
    x, y, px, py, lam = S("x"), S("y"), S("p_x"), S("p_y"), S("lam")
    g = sp.Rational(981, 100)
    same_up_to_sign([c for gen in db.generations for c in gen],
                    [S("p_lam"), x**2 + y**2 - 1, x * px + y * py,
                     lam * (x**2 + y**2) + px**2 + py**2 - g * y])
    assert (db.first_class, db.second_class, db.degrees_of_freedom) == (0, 4, 1)
    z = db.algebra.variables
    D = db.dirac_bracket
    r2 = x**2 + y**2
    for qi in (x, y):
        for pj, qj in ((px, x), (py, y)):
            expected = (1 if qi == qj else 0) - qi * qj / r2
            assert sp.simplify(D[z.index(qi), z.index(pj)] - expected) == 0


def test_a_force_on_a_coordinate_without_inertia_is_inconsistent():
    # L = x'^2/2 + y: p_y = 0 and {p_y, H_c} = {p_y, p_x^2/2 - y} = 1: 0 = 1.
    db = chain("inconsistent_force.toml")
    assert db.status == "inconsistent" and not db.consistent
    assert "0 = 1" in db.run.inconsistency
    assert db.first_class is None and db.degrees_of_freedom is None


def test_einbein_particle_by_hand():
    # p_e = 0 -> {p_e, H_c} = -(p.p + m^2)/2 (H_c = e (p.p + m^2)/2, metric -+++);
    # both first class, dof (10 - 4)/2 = 3; G = eps' p_e + eps (p.p + m^2)/2.
    db = chain("einbein_particle.toml")
    p = [S(f"p_x{i}") for i in range(4)]
    shell = -p[0]**2 + p[1]**2 + p[2]**2 + p[3]**2 + 1
    same_up_to_sign(db.generations[1], [shell])
    assert (db.first_class, db.second_class, db.degrees_of_freedom) == (2, 0, 3)
    (g,) = db.gauge_generators
    terms = dict(g.terms)
    assert terms[1] == S("p_e") and sp.expand(terms[0] - shell / 2) == 0


def first_class_by_zero_rows(classes):
    """The rule of scripts that call a constraint first class when its row of brackets
    vanishes: wrong where a combination is first class and no single constraint is."""
    return len(classes.individually_first_class)


def test_classes_are_counted_by_rank_not_by_zero_rows():
    # L = x y' + x z': p_x = 0, p_y = x, p_z = x; H_c = 0. B = [[0, 1, 1], [-1, 0, 0],
    # [-1, 0, 0]] has rank 2 and no zero row: 2 second class and p_y - p_z first class;
    # dof (6 - 2 - 2)/2 = 1. The zero-row rule finds no first-class constraint.
    db = dirac_bergmann(System(["x", "y", "z"], "x*y_dot + x*z_dot"))
    assert (db.first_class, db.second_class, db.degrees_of_freedom) == (1, 2, 1)
    assert first_class_by_zero_rows(db.classes) == 0  # the planted rule: it would fail
    (gamma,) = db.primary_first_class
    same_up_to_sign([gamma], [S("p_y") - S("p_z")])


def test_an_irregular_constraint_is_replaced_by_its_regular_equivalent_and_said():
    # L = (x'^2 + y'^2)/2 + w y with the holonomic x^2 = 0 (gradient 2x = 0 where it
    # holds): replaced by x = 0. Then x -> p_x (-> lambda fixed), p_w -> y -> p_y -> w
    # (-> u fixed): six second-class constraints, dof 0.
    db = dirac_bergmann(System(["x", "y", "w"], "(x_dot**2 + y_dot**2)/2 + w*y",
                               holonomic=["x**2"]))
    assert [(lab, str(g), str(r)) for lab, g, r in db.replaced] == [("holonomic[0]", "x**2", "x")]
    assert db.irregular == ()
    assert (db.first_class, db.second_class, db.degrees_of_freedom) == (0, 6, 0)
    assert any("x**2 = 0 is irregular" in w for w in db.warnings)


def test_a_squared_secondary_is_kept_regular():
    # {p_z, H_c} = -dH_c/dz = x^2 (H_c = |p|^2/2 - z x^2): stored as x = 0 (the same zero
    # set, a regular equation), then p_x; p_z first class, (x, p_x) second class.
    db = dirac_bergmann(System(["x", "y", "z"], "(x_dot**2 + y_dot**2)/2 + z*x**2"))
    same_up_to_sign(db.generations[1], [S("x")])
    assert db.irregular == ()
    assert (db.first_class, db.second_class, db.degrees_of_freedom) == (1, 2, 1)


def test_yang_mills_su2_homogeneous_fields():
    # 12 coordinates A_i^a, B^a (= A_0^a); E_i^a = A_i^a' + g eps_abc B^b A_i^c. Primary
    # p_B^a, secondary Gauss's law; all 6 first class, dof (24 - 12)/2 = 6; G_0 carries
    # the non-abelian term eps_abc B^b p_B^c so that {G_0, H} is primary. The scene is
    # written by examples/singular/make_yang_mills_su2.py.
    db = chain("yang_mills_su2.toml")
    assert [len(g) for g in db.generations] == [3, 3]
    assert (db.first_class, db.second_class, db.degrees_of_freedom) == (6, 0, 6)
    assert len(db.gauge_generators) == 3 and all(g.checked.value for g in db.gauge_generators)
    g0 = dict(db.gauge_generators[0].terms)[0]
    assert g0.coeff(S("B2") * S("p_B3")) != 0  # the non-abelian correction
    # Gauss's law of colour 1 is the rotation generator sum_i (A_i2 p_Ai3 - A_i3 p_Ai2)
    gauss = sum(S(f"A{i}2") * S(f"p_A{i}3") - S(f"A{i}3") * S(f"p_A{i}2") for i in (1, 2, 3))
    same_up_to_sign([g0.subs({S(f"p_B{a}"): 0 for a in (1, 2, 3)})], [gauss])


def test_legendre_image_by_hand():
    # W = [[1, 1], [1, 1]] for L = (x' + y')^2/2 + x: ker W = (1, -1), phi = p_x - p_y;
    # H_c = p^2/2 - x with p = p_x on the primary surface.
    image = legendre_image(System(["x", "y"], "(x_dot + y_dot)**2/2 + x"))
    assert image.rank == 1
    same_up_to_sign(image.constraints, [S("p_x") - S("p_y")])
    assert sp.expand(image.canonical_hamiltonian - (S("p_x")**2 / 2 - S("x"))) == 0


def test_what_is_not_built_is_refused_by_key():
    with pytest.raises(ValidationError, match="lagrangian: W depends on the velocities and "
                                              "L is not algebraic"):
        legendre_image(System(["x", "y"], "exp(x_dot) + y"))


def test_a_chetaev_constraint_off_ker_w_by_hand():
    # L = (x'^2 + y'^2)/2 - g y + lam (x^2 + y^2 - 1)/2 with x'^2 + y'^2 = 1: on T*Q the
    # speed is p_x^2 + p_y^2 - 1 (no u: lam' is not in it); generations (p_lam), (the speed
    # and the ring), (x p_x + y p_y), (the one that fixes lam); 5 constraints, their 5 x 5
    # bracket matrix antisymmetric of rank 4: 1 first-class combination, 4 second class.
    db = dirac_bergmann(System(["x", "y", "lam"],
                               "(x_dot**2 + y_dot**2)/2 - g*y + lam*(x**2 + y**2 - 1)/2",
                               constraints=["x_dot**2 + y_dot**2 - 1"],
                               parameters={"g": 9.81}))
    assert [len(g) for g in db.generations] == [1, 2, 1, 1]
    same_up_to_sign(db.generations[1], [S("p_x")**2 + S("p_y")**2 - 1,
                                        S("x")**2 + S("y")**2 - 1])
    assert (db.first_class, db.second_class, db.run.free_multiplier_symbols) == (1, 4, ())


def test_the_verdict_is_at_the_values_put_in_exactly():
    s = System(["x", "y"], "B*x*y_dot", parameters={"B": 0.1})
    db = dirac_bergmann(s)
    same_up_to_sign(db.image.constraints, [S("p_x"), S("p_y") - S("x") / 10])
    assert db_module.at_parameter_values(s).parameters == ()


def test_from_mechanics_takes_a_singular_lagrangian():
    from sympy.physics.mechanics import dynamicsymbols

    from nhham import from_mechanics

    x, y = dynamicsymbols("x y")
    B, k = sp.symbols("B k")
    s = from_mechanics(B * x * y.diff() - k * (x**2 + y**2) / 2, [x, y],
                       parameters={"B": 2.0, "k": 1.0})
    assert not s.regular_lagrangian
    db = dirac_bergmann(s)
    assert (db.second_class, db.degrees_of_freedom) == (2, 1)


def test_an_inductor_capacitor_loop_oscillates_at_one_over_root_lc():
    # L = ell qL'^2/2 - qC^2/(2 C), Kirchhoff: qL' = qC'. p_qC = 0 (primary); v = dH_T/dp
    # gives qC' = u_1, so the current law fixes u_1 = p_qL/ell; the tangency of p_qC fixes
    # lambda_1 = qC/C. The motion: qC' = p_qL/ell, p_qL' = -qC/C: omega^2 = 1/(ell C).
    ell, cap = sp.symbols("ell Cap", positive=True)
    db = dirac_bergmann(System(["qL", "qC"], "ell*qL_dot**2/2 - qC**2/(2*Cap)",
                               constraints=["qL_dot - qC_dot"],
                               parameters={"ell": None, "Cap": None}))
    same_up_to_sign([c for gen in db.generations for c in gen], [S("p_qC")])
    assert db.fixed_multipliers[S("u_1")] == S("p_qL") / S("ell")
    z = list(db.algebra.variables)
    rate = dict(zip(z, db.motion))
    J = sp.Matrix([[sp.diff(rate[a], b) for b in (S("qC"), S("p_qL"))]
                   for a in (S("qC"), S("p_qL"))]).subs({S("ell"): ell, S("Cap"): cap})
    assert set(J.eigenvals()) == {sp.I / sp.sqrt(ell * cap), -sp.I / sp.sqrt(ell * cap)}
    assert db.degrees_of_freedom is None and db.gauge_generators == ()


@pytest.mark.parametrize("resistor", ["qC", "qL"])
def test_a_resistor_damps_the_loop_by_hand(resistor):
    # R q'^2/2 on either branch: ell q'' + R q' + q/C = 0 (the current law makes the two
    # currents one). On the capacitor's branch the force -R qC' = -R u_1 moves with the
    # primary's multiplier: the tangency of p_qC fixes lambda_1 = R u_1 + qC/C.
    ell, cap, R = sp.symbols("ell Cap R", positive=True)
    db = dirac_bergmann(System(["qL", "qC"], "ell*qL_dot**2/2 - qC**2/(2*Cap)",
                               constraints=["qL_dot - qC_dot"],
                               parameters={"ell": None, "Cap": None, "R": None},
                               dissipation=f"R*{resistor}_dot**2/2"))
    u = db.fixed_multipliers[S("u_1")]
    assert u == S("p_qL") / S("ell")
    lam = db.fixed_multipliers[S("lambda_1")]
    expected = S("qC") / S("Cap") + (S("R") * u if resistor == "qC" else 0)
    assert sp.simplify(lam - expected) == 0
    rate = dict(zip(db.algebra.variables, db.motion))
    J = sp.Matrix([[sp.diff(rate[a], b) for b in (S("qC"), S("p_qL"))]
                   for a in (S("qC"), S("p_qL"))]).subs({S("ell"): ell, S("Cap"): cap,
                                                         S("R"): R})
    s = sp.Symbol("s")
    assert sp.simplify(J.charpoly(s).as_expr() - (s**2 + R / ell * s + 1 / (ell * cap))) == 0
    assert db.gauge_generators == ()


def test_inputs_are_refused_on_a_singular_l():
    with pytest.raises(InputError, match="inputs: inputs on a singular Lagrangian"):
        dirac_bergmann(System(["x", "y"], "x*y_dot - y**2/2", forces={"x": "F"},
                              inputs=["F"]))


def test_a_cubic_resistor_makes_the_capacitor_current_a_state_by_hand():
    # R(qC') = r qC'^4/4: the force -r u^3 is not affine in u = qC' (W's null direction):
    # u_1 is state, the current law p_qL/ell - u_1 = 0 a constraint, the tangency of p_qC
    # fixes lambda_1 = qC/Cap + r u_1^3 and that of the law u_1' = p_qL'/ell.
    db = dirac_bergmann(System(["qL", "qC"], "ell*qL_dot**2/2 - qC**2/(2*Cap)",
                               constraints=["qL_dot - qC_dot"],
                               parameters={"ell": None, "Cap": None, "r": None},
                               dissipation="r*qC_dot**4/4"))
    u, lam = S("u_1"), S("lambda_1")
    assert db.velocities_as_state == (u,)
    assert sp.simplify(db.fixed_multipliers[lam] - (S("qC") / S("Cap") + S("r") * u**3)) == 0
    rate = dict(zip(db.variables, db.motion))
    assert rate[S("qC")] == u
    assert sp.simplify(rate[S("p_qL")] + S("qC") / S("Cap") + S("r") * u**3) == 0
    assert (db.first_class, db.second_class, db.degrees_of_freedom) == (1, 0, None)
    # compare is not built for it, and says so
    assert db.equivalence.why_not and "not built" in db.equivalence.why_not


def test_a_landau_level_in_a_field_that_changes_with_t_by_hand():
    # L = B(t) x y' - (x^2 + y^2)/2, B = 2 + sin t. Euler-Lagrange: y' = x/B and
    # d/dt(B x) = -y, x' = -(y + B' x)/B: the tangency of p_y - B(t) x carries -B'(t) x.
    # The chain on TQ agrees through Leg, whose dp/dt = B' x enters the push-forward.
    t, x, y = S("t"), S("x"), S("y")
    B = 2 + sp.sin(t)
    db = dirac_bergmann(System(["x", "y"], "(2 + sin(t))*x*y_dot - (x**2 + y**2)/2"))
    rate = dict(zip(db.algebra.variables, db.motion))
    assert sp.simplify(rate[x] + (y + sp.cos(t) * x) / B) == 0
    assert sp.simplify(rate[y] - x / B) == 0
    assert sp.simplify(db.dirac_bracket[0, 1] + 1 / B) == 0
    assert db.gauge_generators == ()
    eq = db.equivalence
    assert eq.agree, eq.to_dict()


def test_relativistic_particle_by_elimination_of_the_velocities():
    # L = -m sqrt(-x'.x') (metric -+++): p = m eta x'/s with s = sqrt(-x'.x'), so
    # p.p = -m^2: one primary constraint p.p + m^2 = 0, and E_L = x'.p - L = -m s + m s = 0
    # (Euler, degree 1): H_c = 0. No secondary; first class; dof (8 - 2)/2 = 3.
    db = chain("relativistic_particle.toml")
    p = [S(f"p_x{i}") for i in range(4)]
    same_up_to_sign(db.image.constraints, [-p[0]**2 + p[1]**2 + p[2]**2 + p[3]**2 + 1])
    assert db.image.canonical_hamiltonian == 0 and db.image.rank == 3
    assert (len(db.generations), db.first_class, db.second_class,
            db.degrees_of_freedom) == (1, 1, 0, 3)


def test_a_square_root_lagrangian_with_a_potential():
    # L = -sqrt(1 - x'^2) ... is regular; a singular one: L = -m sqrt(-x'.x') in 1 + 1
    # dimensions with a field A = (0, B x0) (a charge): p1 - B x0 = m x1'/s, p0 = -m x0'/s:
    # (p1 - B x0)^2 - p0^2 + m^2 = 0, H_c = 0; its bracket with itself is 0: first class.
    db = dirac_bergmann(System(["x0", "x1"], "-sqrt(x0_dot**2 - x1_dot**2) + 2*x0*x1_dot"))
    p0, p1, x0 = S("p_x0"), S("p_x1"), S("x0")
    same_up_to_sign(db.image.constraints, [(p1 - 2 * x0)**2 - p0**2 + 1])
    assert (db.first_class, db.second_class, db.degrees_of_freedom) == (1, 0, 1)


def test_the_equivalence_check_fails_for_another_lagrangian():
    # The Landau level's chain on T*Q (k = 1) against the chain on TQ of k = 3: the drift
    # velocities differ (x' = -k y/B), so Leg(M_f^L) is not in M_f^H.
    import dataclasses

    from nhham.hamiltonian.equivalence import equivalence

    db = dirac_bergmann(System(["x", "y"], "2*x*y_dot - (x**2 + y**2)/2"))
    assert equivalence(db).agree
    other = System(["x", "y"], "2*x*y_dot - 3*(x**2 + y**2)/2")
    planted = equivalence(dataclasses.replace(db, system=other))
    assert not planted.agree


def test_the_lagrangian_chain_finds_the_second_order_constraints():
    # L = B x y' - V: W = 0, so the Euler-Lagrange equations are the constraints
    # B y' - V_x = 0 and -B x' - V_y = 0 (x' = -V_y/B, y' = V_x/B), which the chain on
    # T*Q does not have (there they are conditions on the multipliers).
    from nhham.lagrangian.singular import lagrangian_chain

    run = lagrangian_chain(System(["x", "y"], "2*x*y_dot - (x**2 + y**2)/2"))
    x, y, vx, vy = S("x"), S("y"), S("x_dot"), S("y_dot")
    same_up_to_sign(run.final_constraints, [2 * vy - x, -2 * vx - y])
    assert run.status == "determined" and run.dimension == 2


def test_where_rank_w_drops_is_said_and_a_parameter_makes_a_case():
    # W = diag(x^2, 1, 0): rank 2, and 1 where x = 0 (said). W = diag(c, 1, 0): c = 0 is a
    # case: L = y'^2/2 - z y, p_x and p_z primary; p_z -> y -> p_y -> z second class,
    # p_x first class: dof (6 - 2 - 4)/2 = 0.
    from nhham.verdict.singular import singular_parametric

    db = dirac_bergmann(System(["x", "y", "z"], "x**2*x_dot**2/2 + y_dot**2/2 - z*y"))
    assert db.image.rank_drops == (S("x"),)
    assert any("may drop where x = 0" in w for w in db.warnings)
    pv = singular_parametric(System(["x", "y", "z"], "c*x_dot**2/2 + y_dot**2/2 - z*y",
                                    parameters={"c": 1.0}))
    assert (pv.generic.first_class, pv.generic.second_class) == (0, 4)
    [(conditions, chain)] = [(c.conditions, c.chain) for c in pv.cases]
    assert conditions == (S("c"),)
    assert (chain.first_class, chain.second_class, chain.degrees_of_freedom) == (1, 4, 0)
