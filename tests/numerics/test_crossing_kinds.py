"""Labels of crossings (issue 43, item 4): the kind is what crosses.

- tests/study/scenes/upright_hoop.toml: an upright hoop rolling at spin w, conservative;
  in (lean, yaw_dot, lean_dot) the eigenvalue 0 of the neighbouring circles and a pair
  with lambda^2 = -(I3 (I3 + m r^2) w^2 - m g r I1) / (I1 (I1 + m r^2)) (the rolling
  disc's closed form, Neimark & Fufaev ch. 3): the real pair +-sigma meets at 0 at
  w_c^2 = m g r I1 / (I3 (I3 + m r^2)) and leaves along the imaginary axis: a real
  crossing (divergence), to Re < 0 as w grows. Before, it was labelled complex, located
  4e-9 off, with a spurious "the linearisation jumps" warning beside it: near w_c the
  three eigenvalues near 0 form a cluster that rounding perturbs by eps^(1/3), 1e-5,
  which the count read as an unstable pair.
- examples/rattleback.toml rocking without spin (w = 0, a grid value): both pairs on the
  imaginary axis, one turning unstable, one stable; the crossings are at w = 0, not at
  -6.5e-16 and 0 ("w = -0 and +0").
- A Jordan block at 0 (LAPACK returns +-1e-8 for it) is not "unstable": each eigenvalue's
  margin is its rounding error estimate where that exceeds the tolerance.
The bicycle's weave (complex) and capsize (real) speeds against the benchmark's
matrices: tests/numerics/test_linearization.py::test_bicycle_weave_and_capsize_speeds.
"""

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from nhham import load_scene
from nhham.journeys import linearize
from nhham.numerics.codegen import numeric_model

ROOT = Path(__file__).resolve().parents[2]
HOOP = ROOT / "tests" / "study" / "scenes" / "upright_hoop.toml"
g, r, m, I1, I3 = 9.81, 0.5, 2.0, 0.25, 0.5
W_C = math.sqrt(m * g * r * I1 / (I3 * (I3 + m * r ** 2)))


def hoop_pair(w):
    """The pair's lambda^2 (the scene's header)."""
    return -(I3 * (I3 + m * r ** 2) * w ** 2 - m * g * r * I1) / (I1 * (I1 + m * r ** 2))


@pytest.fixture(scope="module")
def hoop():
    scene = load_scene(HOOP)
    return scene, numeric_model(scene.steady_system())


def test_the_hoop_s_critical_spin_is_a_real_crossing(hoop):
    scene, model = hoop
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        answer = linearize(scene, model=model, sweep=("w", np.linspace(0.0, 4.0, 5)))
    swept = answer.payload["sweep"]
    (c,) = swept.crossings
    assert c.kind == "real" and c.direction == -1
    assert abs(c.value - W_C) < 1e-9 * W_C
    assert swept.unlocated == () and answer.warnings == ()
    assert not [w for w in caught if "jumps" in str(w.message)]
    # below w_c the falling pair: unstable; above it a centre, which linearisation
    # cannot decide
    assert swept.stable == (False, False, False, None, None)


@pytest.mark.parametrize("w", [1.0, 3.0])
def test_the_hoop_s_eigenvalues_against_the_closed_form(hoop, w):
    scene, model = hoop
    lin = linearize(scene, model=model.with_parameters(w=w)).payload["linearization"]
    root = np.sqrt(complex(hoop_pair(w)))
    def key(z):
        return round(z.imag, 6), round(z.real, 6)

    want = sorted([root, -root, 0.0], key=key)
    got = sorted(lin.eigenvalues, key=key)
    assert np.abs(np.array(got) - np.array(want)).max() < 1e-9


def test_the_rocking_rattleback_s_pairs_exchange_at_zero_spin():
    scene = load_scene(ROOT / "examples" / "rattleback.toml")
    swept = linearize(scene, method="complex-step",
                      sweep=("w", np.linspace(-30.0, 30.0, 5))).payload["sweep"]
    at_zero = [c for c in swept.crossings if abs(c.value) < 1.0]
    assert [c.value for c in at_zero] == [0.0, 0.0]
    assert sorted(c.direction for c in at_zero) == [-1, 1]
    assert all(c.kind == "complex" for c in swept.crossings)


def test_a_cluster_at_zero_is_on_the_axis_to_its_rounding():
    """[[0, 1], [e, 0]] with e = 1e-16: eigenvalues +-1e-8 by LAPACK, a Jordan block at
    0 to rounding: inside their margins (not unstable), and the count of unstable ones
    (what a crossing changes) is 0."""
    from nhham.numerics.spectra import spectra, unstable_counts

    A = np.array([[[0.0, 1.0], [1e-16, 0.0]], [[0.0, 1.0], [1e-6, 0.0]]])
    ev, margins, tol, verdict = spectra(A)
    assert np.abs(ev[0]).max() == pytest.approx(1e-8, rel=1e-6)
    assert verdict.tolist() == [-1, 0]         # 1e-3 is resolved: unstable
    assert unstable_counts(ev, margins).tolist() == [0, 1]
    assert (margins[0] > 1e-8).all() and (margins[1] == tol[1]).all()
