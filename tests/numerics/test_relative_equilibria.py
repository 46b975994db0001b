"""The rattleback's relative equilibria (``nhham linearize`` of a motion along a
``[symmetry]``) against an independent KanesMethod model in body-frame speeds
(tests/numerics/rattleback_kane.py): the four nonzero eigenvalues at both spin
directions, and the spin rate where the positive direction turns stable, located by the
sweep and by the single command, against the Kane route's root.

In co-moving variables nhham linearises X - w Xi on M_1 (roll, pitch and two
velocities); the Kane route linearises the reduced equations in (roll, pitch, omega_B),
whose Jacobian has the eigenvalue 0 of the neighbouring spins besides. Both are the
linearisation of the one reduced dynamics on M_1 / SE(2), so the nonzero spectra agree.
"""

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from nhham import load_scene
from nhham.journeys import linearize

from rattleback_kane import reduced_jacobian

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
sys.path.insert(0, str(EXAMPLES))

import make_rattleback  # noqa: E402  (the generator's parameter values)

VALUES = {k: v for k, v in make_rattleback.VALUES.items() if k != "w"}
TOL = 1e-8


def kane_spectrum(w):
    """The Kane route's eigenvalues at spin w, the zero one (the spin family) dropped."""
    ev = np.linalg.eigvals(reduced_jacobian(VALUES, w))
    return _sorted(ev[np.argsort(np.abs(ev))][1:])


def _sorted(ev):
    ev = np.asarray(ev, dtype=complex)
    return ev[np.lexsort((ev.imag, np.round(ev.real, 6)))]


@pytest.fixture(scope="module")
def command():
    """``nhham linearize`` of the scene at spin w (``--set w=...``: the journey at the
    model's parameter values; one scene and one generated model for all)."""
    from nhham.numerics.codegen import numeric_model

    scene = load_scene(EXAMPLES / "rattleback.toml")
    model = numeric_model(scene.steady_system())

    def at(w, sweep=None):
        return linearize(scene, sweep=sweep, model=model.with_parameters(w=w))

    return at


@pytest.mark.parametrize("w", [40.0, -40.0, 7.5])
def test_eigenvalues_against_kanes_method(command, w):
    lin = command(w).payload["linearization"]
    assert lin.relative["rate"] == w and lin.relative["group"] == ("x", "y")
    assert lin.coordinates == ("roll", "pitch", "x_dot", "y_dot")
    got, want = _sorted(lin.eigenvalues), kane_spectrum(w)
    assert np.abs(got - want).max() <= TOL * max(1.0, np.abs(want).max()), (got, want)
    # the group block: the translations seen from a frame turning at w
    assert sorted(z.imag for z in lin.relative["group_eigenvalues"]) == pytest.approx(sorted([-w, w]))


def test_both_spin_directions_and_the_verdicts(command):
    """Time reversal maps the spin w to -w and the spectrum to its negative; at w = 40 the
    scene's spin is asymptotically stable, at -40 unstable (the header's figures)."""
    plus = command(40.0).payload["linearization"]
    minus = command(-40.0).payload["linearization"]
    assert plus.stable is True and minus.stable is False
    assert np.abs(_sorted(-plus.eigenvalues) - _sorted(minus.eigenvalues)).max() < 1e-9
    assert plus.eigenvalues[0] == pytest.approx(-7.79955071461 + 31.2539415227j, abs=1e-9)


def test_the_spin_where_the_positive_direction_turns_stable(command):
    """The sweep's crossing, the Kane route's root of max Re, and the single command on
    both sides of it agree."""
    def kane_top(w):
        return kane_spectrum(w).real.max()

    root = brentq(kane_top, 20.0, 30.0, xtol=1e-13)
    swept = command(40.0, sweep=("w", np.linspace(5.0, 45.0, 9))).payload["sweep"]
    (crossing,) = swept.crossings
    assert crossing.direction < 0 and abs(crossing.value - root) < TOL * root
    assert abs(abs(crossing.eigenvalue.imag) - root) < 1e-6   # the pair +-i w_c
    below = command(crossing.value - 1e-4).payload["linearization"]
    above = command(crossing.value + 1e-4).payload["linearization"]
    at = command(crossing.value).payload["linearization"]
    assert below.stable is False and above.stable is True
    assert abs(at.eigenvalues.real.max()) < 1e-7
