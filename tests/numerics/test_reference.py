"""The high-precision reference (nhham.numerics.reference) against the Chaplygin sleigh's
closed form (tests/numerics/test_exact_solutions.py), far beyond float64: directly in
mpmath, and as simulate's method "reference"."""

from __future__ import annotations

import numpy as np

from nhham.numerics.codegen import numeric_model
from nhham.numerics.integrate import simulate

from test_exact_solutions import chaplygin_sleigh, sleigh_exact, sleigh_state


def test_reference_method_through_simulate(sleigh):
    res = simulate(sleigh, (0, 1.0), sleigh_state(), method="reference", reference_digits=25,
                   t_eval=[0.5, 1.0], warn=False)
    assert res.success and np.allclose(res.t, [0.5, 1.0])
    u, w, th = sleigh_exact(np.array(1.0))
    assert abs(res["theta_dot"][-1] - w) < 1e-15
    assert res.settings["digits"] == 25 and res.settings["error_estimate"] < 1e-18


def test_chaplygin_sleigh_reference_integrator():
    """The mpmath reference reproduces the closed form far beyond float64
    (initial state built on M_1 in 40-digit arithmetic)."""
    import mpmath

    from nhham.numerics.reference import reference_solution

    model = numeric_model(chaplygin_sleigh())
    with mpmath.workdps(40):
        # The model's parameters are float64 numbers: use exactly those values.
        m, I, a = mpmath.mpf(1.0), mpmath.mpf(0.3), mpmath.mpf(0.5)
        th0, u0, w0 = mpmath.mpf(3) / 10, mpmath.mpf(4) / 10, mpmath.mpf(3) / 2
        y0 = [mpmath.mpf(0), mpmath.mpf(0), th0,
              u0 * mpmath.cos(th0) - a * w0 * mpmath.sin(th0),
              u0 * mpmath.sin(th0) + a * w0 * mpmath.cos(th0), w0]
        ref = reference_solution(model, y0, (0, 2.0), digits=30, t_eval=[2.0])
        assert ref.status == 0
        J = I + m * a * a
        U = mpmath.sqrt(u0**2 + J * w0**2 / m)
        k = a * m * U / J
        c = mpmath.atanh(u0 / U)
        s = k * 2 + c
        u = U * mpmath.tanh(s)
        w = mpmath.sqrt(m / J) * U / mpmath.cosh(s)
        yf = ref.y_mp[-1]
        u_num = mpmath.cos(yf[2]) * yf[3] + mpmath.sin(yf[2]) * yf[4]
        assert abs(u_num - u) < mpmath.mpf(10) ** -22
        assert abs(yf[5] - w) < mpmath.mpf(10) ** -22


def test_a_state_beyond_the_range_of_the_numbers_stops_the_reference():
    """V = -exp(exp(x)) at x = 200: exp(x) = 7e86, and mpmath, which has no overflow,
    shifted a mantissa by 10^87 bits for exp of it (a MemoryError: an internal error of
    the command). The run stops at its start, non-finite, keeping the initial state."""
    import nhham
    from nhham.numerics.reference import reference_solution
    from nhham.numerics.status import Status

    model = numeric_model(nhham.System(["x"], "x_dot**2/2 + exp(exp(x))"), backend="numpy")
    ref = reference_solution(model, [200.0, 0.0], (0, 1), digits=20)
    assert ref.status == Status.NONFINITE and "beyond the range" in ref.message
    assert ref.t.tolist() == [0.0] and ref.y[:, 0].tolist() == [200.0, 0.0]
