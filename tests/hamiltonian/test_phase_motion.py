"""The motion of a singular Lagrangian on M_f, run and linearised (``simulate`` and
``linearize`` of a singular scene), against closed forms and second formulations derived
by hand: the Euler-Lagrange equations of the same system in other coordinates, integrated
here with scipy on their own."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nhham import loads_scene
from nhham.errors import InputError
from nhham.journeys.singular_motion import linearize_singular, simulate_singular
from tests.cli.conftest import EXAMPLES

GALLERY = EXAMPLES / "singular"
TIGHT = {"rtol": 1e-11, "atol": 1e-13}


def scene(text, **kw):
    return loads_scene(text, check_initial=False, **kw)


def final(answer):
    return dict(zip(answer.data["state"], answer.data["y_final"]))


def imaginary_parts(answer):
    return sorted(round(im, 10) + 0.0 for _, im in answer.data["eigenvalues"])


def test_landau_level_rotates_at_k_over_b():
    # y' = k x/B, x' = -k y/B: x = cos(k t/B), y = sin(k t/B) from (1, 0).
    s = scene("""
coordinates = ["x", "y"]
parameters = { B = 3.0, k = 2.0 }
lagrangian = "B*x*y_dot - k*(x**2 + y**2)/2"
[initial]
x = 1.0
y = 0.0
""")
    answer = simulate_singular(s, t_end=1.7, options=TIGHT)
    z = final(answer)
    assert z["x"] == pytest.approx(math.cos(2 * 1.7 / 3), abs=1e-9)
    assert z["y"] == pytest.approx(math.sin(2 * 1.7 / 3), abs=1e-9)
    assert z["p_y"] == pytest.approx(3 * z["x"], abs=1e-9)          # on M_f: p_y = B x
    assert answer.data["singular"]["second_class"] == 2
    assert answer.data["energy_drift_rel"] < 1e-9


def test_christ_lee_in_its_gauge_is_the_radial_oscillator():
    # xi = 0, x2 = 0: x1'' = -k x1^3 (the potential k r^4/4), integrated here on its own.
    answer = simulate_singular(scene((GALLERY / "christ_lee.toml").read_text()),
                               t_end=2.0, options=TIGHT)
    ref = solve_ivp(lambda t, y: [y[1], -y[0] ** 3], (0, 2.0), [1.0, 0.0], rtol=1e-12,
                    atol=1e-14)
    z = final(answer)
    assert z["x1"] == pytest.approx(ref.y[0, -1], abs=1e-8)
    assert z["p_x1"] == pytest.approx(ref.y[1, -1], abs=1e-8)
    assert (z["x2"], z["xi"], z["p_x2"]) == (0.0, 0.0, 0.0)
    s = answer.data["singular"]
    assert s["gauge"] == ["xi", "x2"] and (s["first_class"], s["second_class"]) == (0, 4)


def test_pendulum_with_its_multiplier_is_the_pendulum():
    # theta'' = -g sin(theta) (x = sin theta, y = -cos theta); the tension solved on M_f
    # from [initial]: lam = g y - v^2 = -g cos(0.3) at rest.
    answer = simulate_singular(scene((GALLERY / "pendulum_multiplier.toml").read_text()),
                               t_end=1.3, options=TIGHT)
    g = 9.81
    ref = solve_ivp(lambda t, y: [y[1], -g * math.sin(y[0])], (0, 1.3), [0.3, 0.0],
                    rtol=1e-12, atol=1e-14)
    theta, omega = ref.y[:, -1]
    z = final(answer)
    assert z["x"] == pytest.approx(math.sin(theta), abs=1e-8)
    assert z["y"] == pytest.approx(-math.cos(theta), abs=1e-8)
    assert z["lam"] == pytest.approx(g * z["y"] - omega ** 2, abs=1e-7)
    assert any("lam = -9.37185" in w for w in answer.warnings)


def test_proca_and_lc_loop_oscillate_at_their_frequencies():
    # Proca: Az'' = -(m^2 + k^2) Az, Az = cos(sqrt(2) t); LC: q'' = -q/(ell C), cos(t/sqrt 2).
    proca = final(simulate_singular(scene((GALLERY / "proca_mode.toml").read_text()),
                                    t_end=2.0, options=TIGHT))
    assert proca["Az"] == pytest.approx(math.cos(math.sqrt(2) * 2), abs=1e-9)
    assert proca["A0"] == pytest.approx(proca["p_Az"], abs=1e-12)   # A0 = k p/m^2
    lc = final(simulate_singular(scene((GALLERY / "lc_circuit.toml").read_text()),
                                 t_end=2.0, options=TIGHT))
    assert lc["qL"] == pytest.approx(math.cos(2 / math.sqrt(2)), abs=1e-9)
    assert lc["qC"] == pytest.approx(lc["qL"], abs=1e-12)           # q_L - q_C conserved


def test_einbein_in_proper_time_moves_on_a_line():
    answer = simulate_singular(scene((GALLERY / "einbein_particle.toml").read_text()),
                               t_end=2.0, options=TIGHT)
    z = final(answer)
    assert (z["x0"], z["x1"], z["e"]) == pytest.approx((2.5, 1.5, 1.0), abs=1e-12)
    assert answer.data["singular"]["first_class"] == 1   # p^2 + m^2: its multiplier is e


@pytest.mark.parametrize("name, expected", [
    ("landau_level.toml", [-0.5, 0.5]),                     # k/B
    ("pendulum_multiplier.toml", [-math.sqrt(9.81), math.sqrt(9.81)]),
    ("proca_mode.toml", [-math.sqrt(2), math.sqrt(2)]),     # sqrt(m^2 + k^2)
    ("lc_circuit.toml", [-math.sqrt(0.5), 0.0, math.sqrt(0.5)]),  # 1/sqrt(ell C), q_L - q_C
])
def test_linearize_gives_the_frequencies_by_hand(name, expected):
    answer = linearize_singular(scene((GALLERY / name).read_text()))
    assert imaginary_parts(answer) == pytest.approx(expected, abs=1e-9)
    assert all(abs(re) < 1e-9 for re, _ in answer.data["eigenvalues"])
    assert answer.data["singular"]["tangent_residual"] < 1e-12


def test_a_state_off_the_final_surface_is_refused_naming_the_constraint():
    text = (GALLERY / "pendulum_multiplier.toml").read_text().replace(
        'x_dot = 0.0\ny_dot = 0.0\n\n# linearize', 'x_dot = 0.0\ny_dot = 0.0\nlam = 1.0\n\n'
        '# linearize', 1)
    with pytest.raises(InputError, match=r"initial: the state is not on the final surface "
                                         r".*secondary\[\d\] ="):
        simulate_singular(scene(text), t_end=1.0)


def test_free_multipliers_are_refused_until_a_gauge_fixes_them():
    with pytest.raises(InputError, match=r"gauge: the multipliers u_1 are free"):
        simulate_singular(scene((GALLERY / "relativistic_particle.toml").read_text()
                                + "[initial]\nx0 = 0.0\n"), t_end=1.0)
    # x1 = 0 does not fix the einbein's reparametrisation: u_1 stays free, said so
    text = (GALLERY / "einbein_particle.toml").read_text().replace(
        'conditions = ["e - 1"]', 'conditions = ["x1"]')
    with pytest.raises(InputError, match=r"gauge: the gauge conditions x1 leave u_1 free"):
        simulate_singular(scene(text), t_end=1.0)


def test_an_inconsistent_chain_and_a_method_that_needs_w():
    with pytest.raises(InputError, match="inconsistent"):
        simulate_singular(scene((GALLERY / "inconsistent_force.toml").read_text()
                                + "[initial]\nx = 0.0\n"), t_end=1.0)
    with pytest.raises(InputError, match=r"simulate.method: rattle .* DOP853"):
        simulate_singular(scene((GALLERY / "landau_level.toml").read_text()), t_end=1.0,
                          options={"method": "rattle", "step": 0.1})


def test_a_steady_state_that_moves_is_not_linearised():
    text = (GALLERY / "landau_level.toml").read_text().replace(
        "[steady]\nx = 0.0", "[steady]\nx = 1.0", 1)
    with pytest.raises(InputError, match=r"steady: not an equilibrium .*y' = 0.5"):
        linearize_singular(scene(text))


def test_the_tangent_chart_matrix_is_similar_to_the_tangent_one():
    answer = linearize_singular(scene((GALLERY / "pendulum_multiplier.toml").read_text()))
    lin = answer.payload["phase"]
    assert np.sort_complex(np.linalg.eigvals(lin.matrix)) == pytest.approx(
        np.sort_complex(np.linalg.eigvals(lin.tangent_matrix)), abs=1e-9)
    assert lin.chart == ("x", "p_x")   # y, lam, p_y, p_lam are functions of them on M_f
    # the reported eigenvalues are those of the orthonormal form
    reported = [complex(*e) for e in answer.data["eigenvalues"]]
    assert sorted(reported, key=lambda e: e.imag) == pytest.approx(
        sorted(np.linalg.eigvals(lin.tangent_matrix), key=lambda e: e.imag), abs=1e-12)


def test_a_resistor_loop_decays_as_the_damped_oscillator():
    # ell q'' + R q' + q/C = 0 from q = 1, q' = 0 (ell = 1, C = 2, R = 0.4):
    # q = exp(-g t) (cos(w t) + g/w sin(w t)), g = R/(2 ell), w^2 = 1/(ell C) - g^2;
    # H_c falls by the resistor's work, which the run carries: the balance closes.
    answer = simulate_singular(scene((GALLERY / "rlc_circuit.toml").read_text()),
                               t_end=3.0, options=TIGHT)
    g, w = 0.2, math.sqrt(0.5 - 0.04)
    q = math.exp(-g * 3) * (math.cos(w * 3) + g / w * math.sin(w * 3))
    z = final(answer)
    assert z["qL"] == pytest.approx(q, abs=1e-9) and z["qC"] == pytest.approx(q, abs=1e-9)
    assert answer.data["energy_drift"] > 0.1
    assert answer.data["energy_balance_residual"] < 1e-9
    lin = linearize_singular(scene((GALLERY / "rlc_circuit.toml").read_text()))
    ev = sorted((complex(*e) for e in lin.data["eigenvalues"]), key=lambda e: e.imag)
    assert ev == pytest.approx([complex(-g, -w), 0, complex(-g, w)], abs=1e-9)


def test_an_isokinetic_bead_goes_round_at_unit_speed():
    # Chetaev's x'^2 + y'^2 = 1 on a ring (multiplier in L) against gravity: from the bottom
    # with x' = 1, (x, y) = (sin t, -cos t); the tension there lam = -g - 1 (y'' = -g + lam y
    # = 1); the reaction -lambda d(phi)/dv does work, which the balance carries.
    answer = simulate_singular(scene((GALLERY / "isokinetic_ring.toml").read_text()),
                               t_end=2.0, options=TIGHT)
    z = final(answer)
    assert (z["x"], z["y"]) == pytest.approx((math.sin(2), -math.cos(2)), abs=1e-8)
    assert any("lam = -10.81" in w for w in answer.warnings)
    assert answer.data["energy_drift"] > 1 and answer.data["energy_balance_residual"] < 1e-8


def test_a_driven_loop_follows_the_forced_oscillator():
    # ell q'' + q/Cap = E0 cos(w t) from q = 1 at rest: q = (1 - a) cos(t/sqrt(ell Cap))
    # + a cos(w t), a = E0/(ell (1/(ell Cap) - w^2)); H_c = E_L depends on t, the run
    # carries dH_c/dt and the balance closes.
    answer = simulate_singular(scene((GALLERY / "driven_lc_circuit.toml").read_text()),
                               t_end=3.0, options=TIGHT)
    a = 0.5 / (0.5 - 1.5**2)
    q = (1 - a) * math.cos(3 / math.sqrt(2)) + a * math.cos(1.5 * 3)
    z = final(answer)
    assert z["qC"] == pytest.approx(q, abs=1e-9) and z["qL"] == pytest.approx(q, abs=1e-9)
    assert answer.data["energy_balance_residual"] < 1e-9
    with pytest.raises(InputError, match="steady: a singular Lagrangian with t"):
        linearize_singular(scene((GALLERY / "driven_lc_circuit.toml").read_text()
                                 + "[steady]\nqL = 0.0\nqC = 0.0\nqL_dot = 0.0\n"
                                   "qC_dot = 0.0\n"))


def test_yang_mills_in_the_temporal_gauge_is_the_x2y2_model():
    # B^a = 0 fixes u_a = B^a' = 0; diagonal fields A_i^a = delta_ia a_i stay diagonal and
    # a_1'' = -g^2 a_1 (a_2^2 + a_3^2) (cyclically), integrated here on its own (g = 1)
    answer = simulate_singular(scene((GALLERY / "yang_mills_su2.toml").read_text()),
                               t_end=5.0, options=TIGHT)

    def x2y2(t, y):
        a, b = y[:3], y[3:]
        return [*b, -a[0] * (a[1]**2 + a[2]**2), -a[1] * (a[0]**2 + a[2]**2),
                -a[2] * (a[0]**2 + a[1]**2)]

    ref = solve_ivp(x2y2, (0, 5.0), [1.0, 0.5, 0.0, 0.0, 0.0, 0.8], rtol=1e-12, atol=1e-14)
    z = final(answer)
    diagonal = [z["A11"], z["A22"], z["A33"], z["p_A11"], z["p_A22"], z["p_A33"]]
    assert diagonal == pytest.approx(list(ref.y[:, -1]), abs=1e-8)
    off = [v for k, v in z.items() if k.lstrip("p_").startswith("A") and k[-2] != k[-1]]
    assert max(abs(v) for v in off) == 0.0


def test_yang_mills_keeps_gauss_law_off_the_diagonal():
    # velocities parallel to the fields satisfy Gauss's law eps_abc A_i^b p_i^c = 0; the
    # run keeps it (a final constraint: measured along the run) and the energy
    rng = np.random.default_rng(7)
    names = [f"A{i}{a}" for i in range(1, 4) for a in range(1, 4)]
    values = dict(zip(names, (float(x) for x in rng.uniform(-1, 1, 9))))
    text = (GALLERY / "yang_mills_su2.toml").read_text()
    head = text[:text.index("[initial]")]
    table = "".join(f"{k} = {v!r}\n{k}_dot = {0.3 * v!r}\n" for k, v in values.items())
    answer = simulate_singular(scene(head + "[initial]\n" + table + "B1 = 0.0\nB2 = 0.0\n"
                                     "B3 = 0.0\n"), t_end=3.0, options=TIGHT)
    assert answer.data["success"]
    assert answer.data["constraint_residual_max"] < 1e-9
    assert answer.data["energy_drift_rel"] < 1e-9
    z = final(answer)
    assert max(abs(z[f"A{i}{a}"]) for i in range(1, 4) for a in range(1, 4) if i != a) > 0.1


def test_a_cubic_resistor_decays_as_its_equation_says():
    # ell q'' + r q'^3 + q/Cap = 0 from q = 1 at rest (ell = 1, Cap = 2, r = 0.5), integrated
    # here on its own; H_c falls by the resistor's work r q'^4, which the balance carries
    answer = simulate_singular(scene((GALLERY / "nonlinear_resistor.toml").read_text()),
                               t_end=6.0, options=TIGHT)
    ref = solve_ivp(lambda t, y: [y[1], -0.5 * y[1]**3 - y[0] / 2], (0, 6.0), [1.0, 0.0],
                    rtol=1e-12, atol=1e-14)
    z = final(answer)
    assert (z["qC"], z["p_qL"], z["u_1"]) == pytest.approx(
        (ref.y[0, -1], ref.y[1, -1], ref.y[1, -1]), abs=1e-8)
    assert answer.data["energy_balance_residual"] < 1e-9


def test_a_nonlinear_current_law_is_the_differential_algebraic_loop():
    # qC'^3 + qC' = qL' (Chetaev, along ker W): ell qL'' = lambda = -qC/(Cap (3 u^2 + 1)),
    # qC' = u the real root of u^3 + u = qL', integrated here as that DAE on its own
    answer = simulate_singular(scene((GALLERY / "nonlinear_current_law.toml").read_text()),
                               t_end=3.0, options=TIGHT)

    def u_of(v):
        roots = np.roots([1.0, 0.0, 1.0, -v])
        return float(roots[np.argmin(abs(roots.imag))].real)

    def dae(t, y):
        u = u_of(y[2])
        return [y[2], u, -y[1] / (2.0 * (1 + 3 * u * u))]

    ref = solve_ivp(dae, (0, 3.0), [0.0, 1.0, 0.0], rtol=1e-12, atol=1e-14)
    z = final(answer)
    assert (z["qL"], z["qC"], z["p_qL"]) == pytest.approx(tuple(ref.y[:, -1]), abs=1e-8)
    assert z["u_1"] == pytest.approx(u_of(ref.y[2, -1]), abs=1e-8)
    assert answer.data["energy_drift"] > 1e-2 and answer.data["energy_balance_residual"] < 1e-9
