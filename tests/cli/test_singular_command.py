"""``nhham`` on the gallery of singular Lagrangians (``examples/singular``).

The expected counts are the hand values of each scene's header (derived in
tests/hamiltonian/test_dirac_bergmann.py); here the command's contract: exit codes, the
JSON keys against the schema, the text, LaTeX, ``--parametric`` and the refusals.
"""

from __future__ import annotations

import json

import jsonschema
import pytest

from tests.cli.conftest import EXAMPLES, run_inprocess

GALLERY = EXAMPLES / "singular"

#: scene -> (status, generations, first class, second class, degrees of freedom, gauge
#: generators), each by hand (the scene's header).
HAND = {
    "gauge_shift.toml": ("underdetermined", [1, 1], 2, 0, 0, 1),
    "christ_lee.toml": ("underdetermined", [1, 1], 2, 0, 1, 1),
    "landau_level.toml": ("determined", [2], 0, 2, 1, 0),
    "proca_mode.toml": ("determined", [1, 1], 0, 2, 1, 0),
    "pendulum_multiplier.toml": ("determined", [1, 1, 1, 1], 0, 4, 1, 0),
    "inconsistent_force.toml": ("inconsistent", [1], None, None, None, 0),
    "einbein_particle.toml": ("underdetermined", [1, 1], 2, 0, 3, 1),
    "lc_circuit.toml": ("determined", [1], 1, 0, None, 0),
    "rlc_circuit.toml": ("determined", [1], 1, 0, None, 0),
    "isokinetic_ring.toml": ("determined", [1, 2, 1, 1], 1, 4, None, 0),
    "driven_lc_circuit.toml": ("determined", [1], 1, 0, None, 0),
    "nonlinear_resistor.toml": ("determined", [2], 1, 0, None, 0),
    "nonlinear_current_law.toml": ("determined", [2], 1, 0, None, 0),
    "relativistic_particle.toml": ("underdetermined", [1], 1, 0, 3, 1),
    "yang_mills_su2.toml": ("underdetermined", [3, 3], 6, 0, 6, 3),
}


def run(*argv):
    rc, out, err = run_inprocess(*argv)
    return rc, (json.loads(out) if out.strip().startswith("{") else out), err


def test_the_gallery_is_the_table():
    assert sorted(p.name for p in GALLERY.glob("*.toml")) == sorted(HAND)


@pytest.mark.parametrize("name", sorted(HAND))
def test_classify_json_by_hand(name, schema):
    rc, env, err = run("classify", str(GALLERY / name), "--json")
    assert rc == 0, err
    jsonschema.validate(env, schema)
    r = env["result"]
    status, generations, fc, sc, dof, gauges = HAND[name]
    assert r["status"] == status
    assert [len(g) for g in r["generations"]] == generations
    assert (r["first_class"], r["second_class"], r["degrees_of_freedom"]) == (fc, sc, dof)
    assert len(r["gauge_generators"]) == gauges
    assert r["lagrangian_rank"]["rank"] < r["n"]
    names = env["scene"]["names"]
    for g in r["gauge_generators"]:
        assert g["parameter"] in names and g["first_class"]["value"] is True


def test_classify_text_and_latex():
    rc, text, _ = run("classify", str(GALLERY / "landau_level.toml"))
    assert rc == 0
    flat = " ".join(text.split())
    assert "a singular Lagrangian (rank W = 0 of 2)" in flat
    assert "{x, y}_D = -1/2" in flat and "degrees of freedom 1" in flat
    rc, latex, err = run("classify", str(GALLERY / "gauge_shift.toml"), "--latex")
    assert rc == 0, err
    assert r"\operatorname{rank} W &= 1" in latex and r"\text{gauge generator}" in latex


def test_the_headline_is_the_one_at_the_values():
    # m = 0 makes the Proca mode a gauge system: the answer there, not the generic one.
    rc, env, _ = run("classify", str(GALLERY / "proca_mode.toml"), "--set", "m=0", "--json")
    assert rc == 0
    r = env["result"]
    assert (r["first_class"], r["second_class"], r["degrees_of_freedom"]) == (2, 0, 0)


def test_parametric_finds_the_massless_case(schema):
    rc, env, err = run("classify", "--parametric", str(GALLERY / "proca_mode.toml"), "--json")
    assert rc == 0, err
    jsonschema.validate(env, schema)
    r = env["result"]
    assert (r["generic"]["first_class"], r["generic"]["second_class"]) == (0, 2)
    cases = {tuple(c["conditions"]): c["verdict"] for c in r["cases"]}
    assert (cases[("m",)]["first_class"], cases[("m",)]["degrees_of_freedom"]) == (2, 0)
    # m = 0 and k = 0: L = Az'^2/2, p_A0 alone first class, one degree of freedom
    assert (cases[("m", "k")]["first_class"], cases[("m", "k")]["degrees_of_freedom"]) == (1, 1)
    assert r["scene_case"] is None


@pytest.mark.parametrize("command", ["bench", "reduce", "hamiltonize"])
def test_other_commands_refuse_a_singular_scene_in_one_line(command):
    rc, out, err = run(command, str(GALLERY / "landau_level.toml"))
    assert rc == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "singular" in lines[0] and f"nhham {command}" in lines[0]
    assert "Traceback" not in err


def test_derive_on_tstar_q_gives_the_motion_by_hand(schema):
    # Landau level, B = 2, k = 1: x' = -k y/B, y' = k x/B (the rotation), u fixed to them.
    rc, env, err = run("derive", "--side", "hamiltonian", str(GALLERY / "landau_level.toml"),
                       "--json")
    assert rc == 0, err
    jsonschema.validate(env, schema)
    r = env["result"]
    field = dict(zip(r["state"], r["field"]))
    assert (field["x"], field["y"]) == ("-y/2", "x/2")
    assert r["energy_name"] == "H_c" and r["free_multiplier_symbols"] == []
    z, M = r["dirac_bracket"]["coordinates"], r["dirac_bracket"]["matrix"]
    assert M[z.index("x")][z.index("y")] == "-1/2"
    # a gauge system keeps its free multiplier in the motion: q2' = u_1
    rc, env, _ = run("derive", "--side", "hamiltonian", str(GALLERY / "gauge_shift.toml"),
                     "--json")
    r = env["result"]
    assert dict(zip(r["state"], r["field"]))["q2"] == "u_1" and r["free_multiplier_symbols"] == ["u_1"]
    rc, latex, _ = run("derive", "--side", "hamiltonian", str(GALLERY / "gauge_shift.toml"),
                       "--latex")
    assert rc == 0 and "H_T" in latex


def test_derive_on_tq_and_an_inconsistent_chain():
    # on TQ the Landau level's drift x = 2 y', y = -2 x' (B = 2, k = 1) differentiated:
    # x'' = -y'/2, y'' = x'/2
    rc, env, err = run("derive", str(GALLERY / "landau_level.toml"), "--json")
    assert rc == 0, err
    r = env["result"]
    field = dict(zip(r["state"], r["field"]))
    assert (field["x_dot"], field["y_dot"]) == ("-y_dot/2", "x_dot/2")
    assert r["energy_name"] == "E_L" and r["free_multiplier_symbols"] == []
    rc, _, err = run("derive", "--side", "hamiltonian", str(GALLERY / "inconsistent_force.toml"))
    assert rc == 2 and "inconsistent" in err and "0 = 1" in err


@pytest.mark.parametrize("name", ["gauge_shift.toml", "landau_level.toml",
                                  "pendulum_multiplier.toml", "lc_circuit.toml",
                                  "rlc_circuit.toml", "driven_lc_circuit.toml"])
def test_compare_finds_the_two_chains_equivalent(name, schema):
    rc, env, err = run("compare", str(GALLERY / name), "--json")
    assert rc == 0, err
    jsonschema.validate(env, schema)
    r = env["result"]
    assert r["agree"] and [c["agree"] for c in r["checks"]] == [True, True, True]
    assert r["lagrangian_side"]["motion_residual"] < 1e-10


def test_compare_says_when_the_tq_chain_cannot_run():
    # the ring's M_5 in TQ (lam' a coordinate there) has no regular block at its points
    rc, _, err = run("compare", str(GALLERY / "isokinetic_ring.toml"))
    assert rc == 3 and "not compared" in err


def test_compare_samples_tq_where_the_square_root_is_real(schema):
    # L = -m sqrt(x0'^2 - |x'|^2) is real for timelike velocities only: the points of TQ
    # are drawn there. Homogeneous of degree 1, W v = 0: the acceleration along v is free
    # (the reparametrisation), and Leg maps M_f^L (dim 8) onto the mass shell (dim 7).
    rc, env, err = run("compare", str(GALLERY / "relativistic_particle.toml"), "--json")
    assert rc == 0, err
    jsonschema.validate(env, schema)
    r = env["result"]
    assert r["agree"] is True
    assert r["lagrangian_status"] == "underdetermined"


def test_a_classify_study_of_a_singular_scene_has_the_massless_case(tmp_path):
    # Proca by hand: m != 0 two second class; m = 0 two first class (underdetermined)
    import xarray as xr

    out = tmp_path / "s.zarr"
    rc, _, err = run("sweep", str(GALLERY / "proca_mode.toml"), "--what", "classify",
                     "--over", "m=0:1:3", "--out", str(out), "--workers", "1")
    assert rc == 0, err
    ds = xr.open_zarr(out)
    assert ds["first_class"].values.tolist() == [2, 0, 0]
    assert ds["second_class"].values.tolist() == [0, 2, 2]
    assert ds["status"].values.tolist() == [1, 0, 0]   # underdetermined, determined
    assert ds["case"].values.tolist() == [0, -1, -1]
    rc, _, err = run("sweep", str(GALLERY / "landau_level.toml"), "--what", "linearize",
                     "--over", "B=1:2:3", "--out", str(tmp_path / "l.zarr"))
    assert rc == 2 and "nhham sweep --what linearize needs W invertible" in err


#: scenes of the gallery with [initial] (simulate) and [steady] (linearize)
RUNS = ["christ_lee.toml", "einbein_particle.toml", "gauge_shift.toml", "landau_level.toml",
        "lc_circuit.toml", "pendulum_multiplier.toml", "proca_mode.toml", "rlc_circuit.toml",
        "isokinetic_ring.toml", "driven_lc_circuit.toml", "yang_mills_su2.toml",
        "nonlinear_resistor.toml", "nonlinear_current_law.toml"]
STEADY = ["landau_level.toml", "lc_circuit.toml", "pendulum_multiplier.toml", "proca_mode.toml",
          "rlc_circuit.toml"]


@pytest.mark.parametrize("name", RUNS)
def test_simulate_runs_the_motion_on_m_f(name, schema):
    rc, env, err = run("simulate", str(GALLERY / name), "--t-end", "1", "--json")
    assert rc == 0, err
    jsonschema.validate(env, schema)
    r = env["result"]
    n = env["scene"]["n"] if "n" in env["scene"] else len(r["state"]) // 2
    assert r["state"][n].startswith("p_")
    # (q, p), and the velocities along ker W where the chain carries them as state
    assert len(r["state"]) == 2 * n + sum(s.startswith("u_") for s in r["state"])
    assert r["success"] and r["constraint_residual_rel_max"] < 1e-8
    assert r["kkt_solve"] is None
    if r["energy_balance_residual"] is None:   # no forces: H_c is conserved
        assert r["energy_drift_rel"] < 1e-8
    else:
        assert r["energy_balance_residual"] < 1e-8


@pytest.mark.parametrize("name", STEADY)
def test_linearize_on_m_f(name, schema):
    rc, env, err = run("linearize", str(GALLERY / name), "--json")
    assert rc == 0, err
    jsonschema.validate(env, schema)
    r = env["result"]
    assert r["stable"] is None and r["method"] == "symbolic"
    assert len(r["matrix"]) == len(r["eigenvalues"]) == len(r["chart"])
    rc, out, err = run("linearize", str(GALLERY / name))
    assert rc == 0 and "(q, p) on the final surface M_f" in out


def test_simulate_text_and_what_a_singular_run_refuses():
    rc, out, err = run("simulate", str(GALLERY / "christ_lee.toml"), "--t-end", "1")
    assert rc == 0, err
    assert "gauge xi; x2 = 0" in out and "final state: x1 = " in out
    for argv, key in ((["--plot", "run.png"], "--plot"), (["--method", "rk4"], "method"),
                      (["--project-initial"], "--project-initial")):
        rc, out, err = run("simulate", str(GALLERY / "landau_level.toml"), *argv)
        assert rc == 2 and key in err and len(err.strip().splitlines()) == 1, err
    rc, out, err = run("simulate", str(GALLERY / "relativistic_particle.toml"))
    assert rc == 2 and "u_1 are free" in err and "[gauge]" in err
    rc, out, err = run("linearize", str(GALLERY / "landau_level.toml"), "--sweep", "k=1:2:3")
    assert rc == 2 and "sweep" in err and "Traceback" not in err


def test_simulate_writes_the_run_of_a_singular_scene(tmp_path):
    # the Landau level from (1, 0): x = cos(t/2), y = sin(t/2), p_y = B x, H_c = k r^2/2
    import numpy as np

    out = tmp_path / "run.csv"
    rc, env, err = run("simulate", str(GALLERY / "landau_level.toml"), "--t-end", "2",
                       "--rtol", "1e-11", "--atol", "1e-13", "--output", str(out), "--json")
    assert rc == 0, err
    assert env["result"]["output"] == str(out)
    header = out.read_text().splitlines()[0].split(",")
    assert header == ["t", "x", "y", "p_x", "p_y", "energy"]
    rows = np.loadtxt(out, delimiter=",", skiprows=1)
    t, x, y = rows[:, 0], rows[:, 1], rows[:, 2]
    assert t[-1] == 2.0
    assert np.max(np.abs(x - np.cos(t / 2))) < 1e-9 and np.max(np.abs(y - np.sin(t / 2))) < 1e-9
    assert np.max(np.abs(rows[:, 4] - 2 * x)) < 1e-9 and np.allclose(rows[:, 5], 0.5)
