"""The published problems (nhham.problems, ``nhham problems``): the catalogue, each
quantity against its source's value, the IFToMM bicycle's files, the command's contract.

The references come from the sources (catalog.toml says what each was checked against),
not from nhham: the benchmark bicycle's Table 2 as transcribed in libbicycle, closed forms
derived by hand, the paper's examples; the rattleback's reversal time against a second
integrator.
"""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from nhham.cli.main import main
from nhham.problems import MEASURES, problem, problems, run
from nhham.problems.catalog import scene_path
from nhham.problems.iftomm import COLUMNS, MANEUVERS
from nhham.problems.measures import closed_form, spectrum_error

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SCHEMA = Path(__file__).resolve().parents[2] / "nhham" / "render" / "schemas" / \
    "output.schema.json"
BICYCLE = ("meijaard2007", "basu_mandal2007", "iftomm_bicycle")
FAST = [p.name for p in problems() if p.name not in BICYCLE]


def test_the_catalogue_has_fifteen_problems_each_cited_and_measurable():
    names = [p.name for p in problems()]
    assert len(names) >= 15 and len(set(names)) == len(names)
    for p in problems():
        assert p.authors and p.source and p.venue and p.checked, p.name
        assert p.quantities, p.name
        for q in p.quantities:
            assert q.measure in MEASURES, (p.name, q.name)
            assert q.precision >= 0
    with pytest.raises(KeyError, match="known: meijaard2007"):
        problem("no such problem")


def test_every_scene_is_the_example_of_that_name():
    """The package's copies (installed without examples/) stay the examples' own."""
    for p in problems():
        packaged = Path(str(scene_path(p)))
        assert packaged.read_bytes() == (EXAMPLES / p.scene).read_bytes(), p.scene


def test_closed_forms_and_spectra_by_hand():
    import nhham

    scene = nhham.loads_scene('coordinates = ["x"]\nparameters = { g = 9.81, r = 0.26 }\n'
                              'lagrangian = "x_dot**2/2"')
    assert closed_form(scene, "sqrt(g/(3*r))") == pytest.approx((9.81 / 0.78) ** 0.5,
                                                                 rel=1e-15)
    assert closed_form(scene, "x_0 + t", t=2.0, initial={"x": 1.0}) == 3.0
    with pytest.raises(ValueError, match="no value for"):
        closed_form(scene, "x_0")
    # greedy matching: the order does not matter, the distance does
    assert spectrum_error([[1, 2], [3, 0]], [[3, 0], [1, 2.5]]) == 0.5


@pytest.fixture(scope="module")
def fast_report():
    return run(FAST)


def test_the_classical_problems_are_within_their_precision(fast_report):
    rows = {(r.problem, r.quantity): r for r in fast_report.rows}
    assert len(rows) == sum(len(problem(n).quantities) for n in FAST)
    bad = [(r.problem, r.quantity, r.value, r.published) for r in fast_report.rows
           if not r.within]
    assert not bad, bad
    # a few against numbers computed here by hand, not by the catalogue's formulas
    disc = rows["rolling_disc_upright", "critical spin rate w_c = sqrt(g/(3 r)), rad/s"]
    assert disc.value == pytest.approx((9.81 / (3 * 0.26)) ** 0.5, rel=1e-12)
    turntable = rows["ball_on_turntable", "rate of the centre's circle, 1/s"]
    assert turntable.value == pytest.approx(2 / 7, rel=1e-10)
    drift = rows["ball_on_tilted_turntable", "mean drift speed 5 g sin(alpha)/(2 Omega), m/s"]
    assert drift.value == pytest.approx(5 * 9.81 * np.sin(0.05) / 2, rel=1e-10)
    # the ball in the cylinder: z_c = -g/(k Omega^2), omega = sqrt(2/7) Omega, Omega = 20
    cylinder = [r for (p, _), r in rows.items() if p == "ball_in_cylinder"][0]
    z_c = -9.81 / (0.4 * 20.0 ** 2)
    assert cylinder.value == pytest.approx(z_c * (1 - np.cos(20 * (2 / 7) ** 0.5 * 10.29)),
                                           abs=1e-9)
    assert rows["deleon1996_example_3_2",
                "stages of the constraint algorithm (M_1, M_2, M_3 = M_f)"].value == 3
    reversal = rows["rattleback_kane_levinson",
                    "time of the first spin reversal from spin -5 rad/s, s"]
    assert 2.0 < reversal.value < 2.7 and "second route" in reversal.note


def test_the_rattleback_s_spins_hold_the_second_route_s_values():
    """catalog.toml holds what the KanesMethod route prints (make_rattleback_references.py),
    and with Kane & Levinson's parameters both spin directions have a growing pair."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from make_rattleback_references import references

    quantities = {q.args["value"]: q for q in problem("rattleback_kane_levinson").quantities
                  if q.measure == "eigenvalues"}
    for w, pairs in references().items():
        assert spectrum_error(quantities[w].published, pairs) < 1e-12, w
        assert max(re for re, _ in pairs) > 0.2   # unstable either way round


def test_a_wrong_density_or_a_wrong_steady_spin_is_caught(fast_report):
    """The invariant-measure rows fail for a density the flow does not keep (the
    exponent's sign turned, the plain volume), and the steady turning for a spin 1 %
    off the relation: the checks can fail."""
    from nhham.problems.measures import invariant_measure, trajectory
    from nhham.problems.runner import Context

    rows = {(r.problem, r.quantity.split(":")[0]): r for r in fast_report.rows}
    veselova = problem("veselova")
    wrong = dict(veselova.quantities[0].args,
                 density="(g1**2/I1 + g2**2/I2 + g3**2/I3)**(-1/2)")
    assert abs(invariant_measure(Context(veselova), wrong).value - 1) > 0.1
    ball = rows["chaplygin_ball", "invariant measure rho = (1 - D (gamma, A gamma))^(-1/2)"]
    assert ball.within and "with the density 1 instead: 0.9" in ball.note
    disc = problem("rolling_disc_steady_turning")
    args = disc.quantities[0].args
    # the relation by hand at lean 0.1, yaw rate 0.5, g = 9.81, r = 0.26
    spin = -5 * 0.5 * np.sin(0.1) / 6 - 2 * 9.81 * np.tan(0.1) / (3 * 0.5 * 0.26)
    off = dict(args, initial=dict(args["initial"], spin_dot=1.01 * spin))
    assert abs(trajectory(Context(disc), off).value - 0.1) > 1e-4
    steady = trajectory(Context(disc), args)
    assert steady.extra["initial"]["spin_dot"] == pytest.approx(spin, rel=1e-14)
    assert steady.value == pytest.approx(0.1, abs=1e-9)


@pytest.fixture(scope="module")
def bicycle_report(tmp_path_factory):
    return run(["meijaard2007", "basu_mandal2007", "iftomm_bicycle"],
               out_dir=tmp_path_factory.mktemp("iftomm"), coarsest=True)


def test_the_benchmark_bicycle_against_table_2(bicycle_report):
    rows = {r.quantity: r for r in bicycle_report.rows if r.problem == "meijaard2007"}
    assert all(r.within for r in rows.values()), [(r.quantity, r.relative_error)
                                                  for r in rows.values()]
    assert rows["weave speed v_w"].value == pytest.approx(4.29238253634111, abs=1e-12)
    assert rows["capsize speed v_c"].value == pytest.approx(6.02426201538837, abs=1e-12)
    # Table 2 at v = 5: weave -0.775341882196 +- 4.464867713788i
    weave = [z for z in rows["eigenvalues at v = 5"].value if z[1] > 0]
    assert weave == [pytest.approx([-0.77534188219585, 4.46486771378823], abs=1e-12)]


def test_a_nonlinear_state_against_basu_mandal_table_1(bicycle_report):
    """Basu-Mandal et al. (2007), Table 1 (as DynamicistToolKit transcribes it): the six
    angular accelerations at their state, to 1e-12 (the table's inputs have 13 decimals)."""
    table = {"theta''": 0.8353281706379, "psi''": -7.8555281128244, "phi''": 0.1205543897884,
             "psi_f''": -4.6198904039403, "beta_r''": 1.8472554144217,
             "beta_f''": 2.4548072904550}
    rows = {r.quantity.split(" ")[0]: r for r in bicycle_report.rows
            if r.problem == "basu_mandal2007"}
    assert set(rows) == set(table)
    for name, value in table.items():
        assert rows[name].value == pytest.approx(value, abs=1e-12), name


def test_the_iftomm_maneuvers_and_their_files(bicycle_report):
    """Energy error <= 1e-10 % (the time: bench/RESULTS.md, no timing here); the files:
    time and the eight columns every 0.01 s over 20 s; the combined one 25 columns."""
    runs = {m.name: m for m in bicycle_report.maneuvers}
    assert set(runs) == set(MANEUVERS)
    for m in runs.values():
        assert m.energy_error_percent <= 1e-10, m
        assert m.t[0] == 0.0 and m.t[-1] == pytest.approx(20.0) and len(m.t) == 2001
        E0, V0 = m.columns[0, 5], m.columns[0, 3]
        # upright at rest but for v0 and the roll rate: V is the masses' weight times
        # their heights (zero at the ground), the same for every maneuver
        assert V0 == pytest.approx(794.1195, rel=1e-12)
        assert m.columns[0, 2] == m.speed and m.columns[0, 1] == m.roll_rate
        assert np.allclose(m.columns[:, 3] + m.columns[:, 4], m.columns[:, 5], rtol=1e-13)
        assert E0 > V0
    files = [Path(f) for f in bicycle_report.files]
    assert [f.name for f in files] == ["M1.txt", "M2.txt", "M3.txt", "bicycleResultsIFToMM.txt"]
    header = files[0].read_text().splitlines()[0]
    assert header.startswith("# IFToMM uncontrolled bicycle, maneuver M1")
    assert all(c in header for c in COLUMNS)
    one = np.loadtxt(files[0])
    assert one.shape == (2001, 9) and np.allclose(one[:, 1:], runs["M1"].columns, rtol=1e-15, atol=1e-300)
    combined = np.loadtxt(files[3])
    assert combined.shape == (2001, 25)
    assert np.allclose(combined[:, 9:17], runs["M2"].columns, rtol=1e-15, atol=1e-300)
    coarse = bicycle_report.iftomm_coarsest
    assert coarse["energy_error_percent"] <= 1e-3 and coarse["rtol"] >= 1e-8


def test_the_command_prints_the_table_and_its_json_meets_the_schema(capsys):
    assert main(["problems", "knife_edge_incline", "deleon1996_example_3_1", "--json"]) == 0
    env = json.loads(capsys.readouterr().out)
    jsonschema.validate(env, json.loads(SCHEMA.read_text()))
    rows = env["result"]["rows"]
    assert [r["problem"] for r in rows] == ["knife_edge_incline"] * 2 + \
        ["deleon1996_example_3_1"] * 2
    assert set(rows[0]) >= {"problem", "quantity", "source", "published", "value",
                            "relative_error", "precision", "within", "time_s", "method"}
    assert env["scene"] is None and env["result"]["all_within"] is True
    assert main(["problems", "--list", "suslov"]) == 0
    assert "Suslov" in capsys.readouterr().out


def test_an_unknown_problem_is_a_usage_error(capsys):
    assert main(["problems", "no_such"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no problem 'no_such'" in err[0] and "known:" in err[0]
