"""Sweeps of a steady motion's stability over a parameter (nhham.numerics.steady_sweep):
crossings of the imaginary axis located by root finding on branches whose eigenvalues are
written down by hand, and a parameter the model does not have. (The bicycle's weave and
capsize speeds, against the benchmark: test_linearization.py.)"""

import numpy as np
import pytest

from nhham import InputError
from nhham.numerics.steady_sweep import sweep, sweep_steady


def test_sweep_locates_a_real_crossing_by_root_finding():
    # a toy branch: lambda(p) = p - 1/3 crossing at exactly 1/3
    class Lin:
        def __init__(self, p):
            self.eigenvalues = np.array([p - 1 / 3, -1.0 + 0j])
            self.tolerance = 1e-12
            self.stable = p < 1 / 3
            self.coordinates = ("a",)

    s = sweep(Lin, "p", np.linspace(0, 1, 4))
    assert len(s.crossings) == 1 and s.crossings[0].kind == "real"
    assert abs(s.crossings[0].value - 1 / 3) < 1e-12


def test_unknown_sweep_parameter(bicycle):
    scene, model = bicycle
    with pytest.raises(InputError, match="'w' is not a parameter"):
        sweep_steady(model, scene.steady.values, "w", [0.0, 1.0])


def test_empty_sweep_is_refused_naming_the_parameter(bicycle):
    scene, model = bicycle
    with pytest.raises(InputError, match="no values of 'v'") as info:
        sweep_steady(model, scene.steady.values, "v", [])
    assert info.value.key == "--sweep"


def _branch(eigenvalues):
    """A linearisation whose eigenvalues at parameter p are ``eigenvalues(p)``."""
    class Lin:
        def __init__(self, p):
            self.eigenvalues = np.array(eigenvalues(p), dtype=complex)
            self.tolerance = 1e-12
            self.stable = bool(np.all(self.eigenvalues.real < -self.tolerance))
            self.coordinates = ("a", "b")

    return Lin


def test_a_complex_pair_crossing_is_a_complex_crossing():
    """(p - 1/2) +- 2i: a Hopf crossing at exactly p = 1/2, from stable to unstable; the
    real eigenvalue -1 crosses nothing."""
    s = sweep(_branch(lambda p: [p - 0.5 + 2j, p - 0.5 - 2j, -1.0]), "p",
              np.linspace(0, 1, 4))
    assert [(c.kind, c.direction) for c in s.crossings] == [("complex", 1)]
    assert abs(s.crossings[0].value - 0.5) < 1e-12
    assert abs(s.crossings[0].eigenvalue - 2j) < 1e-12
    assert list(s.stable) == [True, True, False, False]


def test_a_real_eigenvalue_going_back_is_a_second_crossing():
    """-(p^2 - 2 p + 3/4) = -(p - 1/2)(p - 3/2): positive on (1/2, 3/2) only, so two
    crossings, one each way, at the roots."""
    s = sweep(_branch(lambda p: [-(p - 0.5) * (p - 1.5), -2.0]), "p", np.linspace(0, 2, 8))
    assert [(c.kind, c.direction) for c in s.crossings] == [("real", 1), ("real", -1)]
    assert np.allclose([c.value for c in s.crossings], [0.5, 1.5], atol=1e-12)


def test_crossings_many_batched_against_known_roots():
    # line k: a real eigenvalue p - r_k (root r_k) and a complex pair whose real part is
    # (p - h_k)^3 (a Hopf crossing at h_k, tangent-free but flat: the slow case for a
    # secant method); the roots are the hand-written numbers, with or without counts
    from nhham.numerics.crossings import crossings_many

    class Lin:
        def __init__(self, p, r, h):
            re = (p - h) ** 3
            self.eigenvalues = np.array([p - r, re + 2j, re - 2j, -1.0 + 0j])
            self.tolerance = 1e-12

    roots = [(1 / 3, 0.7), (0.2, 0.45), (np.sqrt(0.5), 1 / np.e)]
    values = np.linspace(0, 1, 6)
    lines = [(values, [Lin(p, r, h) for p in values]) for r, h in roots]

    def spectra_at(requests):
        return [Lin(p, *roots[k]) for k, p in requests]

    counts = [[int(np.sum(s.eigenvalues.real > s.tolerance)) for s in spectra]
              for _, spectra in lines]
    for found in (crossings_many(spectra_at, lines, xtol=1e-12).crossings,
                  crossings_many(spectra_at, lines, xtol=1e-12, counts=counts).crossings):
        for (r, h), cs in zip(roots, found):
            assert [c.kind for c in cs] == sorted(["real", "complex"],
                                                  key=lambda k: r if k == "real" else h)
            real = next(c for c in cs if c.kind == "real")
            hopf = next(c for c in cs if c.kind == "complex")
            assert abs(real.value - r) < 1e-11 and real.direction == 1
            # |(p - h)^3| <= tolerance within 1e-4 of h: the crossing is where the real
            # part is zero to the tolerance, so the bound is the cube root of it
            assert abs(hopf.value - h) < 2e-4 and abs(abs(hopf.eigenvalue.imag) - 2) < 1e-9


def test_a_steady_state_of_a_time_dependent_lagrangian_is_refused_before_the_lift():
    """L with 0.5/t: the lift onto M_1 evaluated the geometry at t = 0 and the generated
    code divided by zero (an internal error of `linearize`, found by the scene fuzz). A
    steady motion needs L autonomous: refused first, naming the lagrangian."""
    import nhham
    from nhham.errors import NhhamError
    from nhham.numerics.steady_sweep import steady_state

    system = nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2 + (1/(2*t))*x_dot*y_dot",
                          ["x_dot + y_dot - 1"])
    model = nhham.numeric_model(system, backend="numpy")
    with pytest.raises(NhhamError, match="depends on time t; a steady motion") as info:
        steady_state(model, dict(x=0.0, y=0.0, x_dot=0.5, y_dot=0.5))
    assert info.value.key == "lagrangian"
