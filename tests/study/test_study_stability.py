"""Stability maps against the bicycle benchmark's closed form (Meijaard et al. 2007).

The map of examples/whipple_bicycle_benchmark.toml over (speed, trail): every point's
verdict against the eigenvalues of the paper's Appendix A matrices
(tests/bicycle_benchmark.py, written from the paper), the located boundaries against
roots of the closed form found here by scipy's brentq, and at the benchmark's trail
against the paper's weave and capsize speeds (section 6: 4.292 382 5 and 6.024 262 0).
"""

import numpy as np
import pytest
from scipy.optimize import brentq

from bicycle_benchmark import BENCHMARK, benchmark_state_matrix
from nhham.study.sweep import sweep

SCENE = "examples/whipple_bicycle_benchmark.toml"
V_WEAVE, V_CAPSIZE = 4.2923825, 6.0242620


def closed_form_crossings(c):
    """(weave, capsize) speeds of the closed form at trail c: where the complex pair's and
    the real eigenvalue's real parts change sign, bracketed on a fine grid."""
    p = dict(BENCHMARK, c=c)

    def branch(v, complex_pair):
        ev = np.linalg.eigvals(benchmark_state_matrix(v, p))
        pick = ev[np.abs(ev.imag) > 1e-9] if complex_pair else ev[np.abs(ev.imag) <= 1e-9]
        return pick.real[np.argmin(np.abs(pick.real))] if pick.size else np.nan

    out = []
    for complex_pair in (True, False):
        vs = np.linspace(0.5, 10, 400)
        f = np.array([branch(v, complex_pair) for v in vs])
        i = np.flatnonzero(np.isfinite(f[:-1]) & np.isfinite(f[1:]) & (np.sign(f[:-1]) !=
                                                                      np.sign(f[1:])))[0]
        out.append(brentq(branch, vs[i], vs[i + 1], args=(complex_pair,), xtol=1e-14))
    return out


@pytest.fixture(scope="module")
def bicycle_map():
    return sweep(SCENE, "linearize", ["v=0:10:41", "c=0.02:0.18:9"], workers=1)


def test_every_point_has_the_closed_form_s_verdict_and_eigenvalues(bicycle_map):
    ds = bicycle_map.dataset
    assert bicycle_map.complete and ds["done"].all() and (ds["status"] == 0).all()
    assert list(ds["row"].values) == ["phi", "delta", "phi_dot", "delta_dot"]
    worst = 0.0
    for i, v in enumerate(ds["v"].values):
        for j, c in enumerate(ds["c"].values):
            expected = np.linalg.eigvals(benchmark_state_matrix(v, dict(BENCHMARK, c=c)))
            got = ds["eigenvalue_real"].values[i, j] + 1j * ds["eigenvalue_imag"].values[i, j]
            worst = max(worst, max(np.min(np.abs(got - z)) for z in expected))
            assert bool(ds["stable"].values[i, j]) == bool(expected.real.max() < 0), (v, c)
    assert worst < 1e-10


def test_boundaries_are_the_closed_form_s_and_the_paper_s(bicycle_map):
    ds = bicycle_map.dataset
    for j, c in enumerate(ds["c"].values):
        count = int(ds["boundary_count"].values[j])
        kinds = list(ds["boundary_kind"].values[j][:count])
        values = ds["boundary"].values[j][:count]
        weave = values[kinds.index(1)]
        capsize = values[kinds.index(0)]
        ref_weave, ref_capsize = closed_form_crossings(c)
        assert abs(weave - ref_weave) < 1e-9 and abs(capsize - ref_capsize) < 1e-9, c
        assert list(ds["boundary_direction"].values[j][[kinds.index(1), kinds.index(0)]]) == [
            -1, 1]   # the weave mode stabilises with speed, the capsize mode destabilises
        if c == 0.08:
            assert abs(weave - V_WEAVE) < 1e-6 and abs(capsize - V_CAPSIZE) < 1e-6


def test_a_steady_entry_that_does_not_move_with_the_parameter_is_solved(tmp_path):
    """A [steady] entry that does not move with the swept parameter (thetaR_dot fixed at
    v/rR for rR = 0.3): it is a dependent velocity of the chart, solved from the
    constraints at every point, so the map is the one of the scene that writes v/rR."""
    text = open(SCENE).read().replace('thetaR_dot = "v/rR"', "thetaR_dot = 16.666666666666668")
    scene = tmp_path / "bike.toml"
    scene.write_text(text)
    fixed = sweep(scene, "linearize", ["rR=0.3,0.35"], workers=1).dataset
    moving = sweep(SCENE, "linearize", ["rR=0.3,0.35"], workers=1).dataset
    assert list(fixed["status"].values) == [0, 0]
    assert np.allclose(fixed["state_matrix"].values, moving["state_matrix"].values,
                       rtol=1e-10, atol=1e-10)


def test_a_controlled_bicycle_s_map_is_its_closed_loop_s():
    """examples/bicycle_steer_control.toml: the study linearises the loop closed by its
    [control] law, as `nhham linearize` does; every point's eigenvalues are the closed
    form's A(v) + B K (B = [0; M^-1], K read off the law) and the boundary is where the
    closed form's real eigenvalue crosses."""
    import sympy as sp

    from bicycle_benchmark import benchmark_matrices
    from nhham.system.scene import load_scene

    scene = "examples/bicycle_steer_control.toml"
    law = load_scene(scene).control["T_delta"]
    K = np.array([[0.0] * 4, [float(sp.diff(law, sp.Symbol(s)))
                              for s in ("phi", "delta", "phi_dot", "delta_dot")]])
    B = np.vstack([np.zeros((2, 2)), np.linalg.inv(benchmark_matrices(BENCHMARK)[0])])

    def closed(v):
        return np.linalg.eigvals(benchmark_state_matrix(v) + B @ K)

    ds = sweep(scene, "linearize", ["v=1:9:9"], workers=1).dataset
    assert "input" not in ds.dims
    for i, v in enumerate(ds["v"].values):
        got = ds["eigenvalue_real"].values[i] + 1j * ds["eigenvalue_imag"].values[i]
        want = closed(v)
        assert np.max(np.abs(np.sort_complex(got) - np.sort_complex(want))) < 1e-6
        assert bool(ds["stable"].values[i]) == bool(np.all(want.real < 0))
    root = brentq(lambda v: np.max(closed(v).real), 2.0, 3.0, xtol=1e-13)
    count = int(ds["boundary_count"].values)
    assert count == 1 and abs(ds["boundary"].values[0] - root) < 1e-6
