"""The generated code behind Python calls (nhham.numerics.kernels): the CPython entry
points of the compiled library against the ctypes route and the numpy backend, and the
inputs they leave to the general path."""

from __future__ import annotations

import numpy as np
import pytest

import nhham
from nhham.numerics.codegen import c_compiler, numeric_model
from nhham.numerics.status import Status

from test_exact_solutions import chaplygin_sleigh, sleigh_state

HAVE_CC = c_compiler() is not None


def test_cpython_entry_points_and_their_fallbacks():
    """The single-state calls through the CPython entry points return fresh
    arrays equal to the ctypes route; inputs they do not take (lists, strided
    or float32 arrays, batches, wrong lengths) go through the general path
    with the same values and errors."""
    system = chaplygin_sleigh()
    ref_model = numeric_model(system, backend="numpy")
    model = numeric_model(system)
    y = sleigh_state()
    ref = ref_model.rhs(0, y)
    a, b = model.rhs(0, y), model.rhs(0, y)
    assert a is not b and np.allclose(a, ref, rtol=1e-13, atol=1e-14)
    a[:] = 0.0
    assert np.allclose(model.rhs(0, y), ref, rtol=1e-13, atol=1e-14)
    strided = np.zeros((6, 2))
    strided[:, 0] = y
    for variant in (list(y), strided[:, 0], y.astype(np.float32)):
        assert np.allclose(model.rhs(0, variant), ref_model.rhs(0, np.asarray(variant, float)),
                           rtol=1e-12, atol=1e-13)
    assert model.rhs(0, np.array([y, y])).shape == (2, 6)
    with pytest.raises(ValueError, match="2n = 6"):
        model.rhs(0, np.zeros(5))
    dy, lam, P, status = model.evaluate(y)
    dy0, lam0, P0, _ = ref_model.evaluate(y)
    assert status == 0 and np.allclose(dy, dy0) and np.allclose(lam, lam0)
    assert P == pytest.approx(P0, abs=1e-13)
    for m in (model, ref_model):
        f = m.field_function()
        z = np.append(y, 123.0)  # the last entry (the work) is ignored
        assert np.allclose(f(z), np.append(ref, P0), rtol=1e-13, atol=1e-13)
        assert np.allclose(f(y), np.append(ref, P0), rtol=1e-13, atol=1e-13)
        fb = m.field_function((1.0, 2.0))
        dyb = ref_model.evaluate(y, (1.0, 2.0))[0]
        assert np.allclose(fb(z)[:6], dyb, rtol=1e-13, atol=1e-13)
    if HAVE_CC and model.compiled.ext is not None:
        block = model.parameter_block()
        out, status = model.compiled.one(y, block.pointer)
        assert status == 0 and np.allclose(model.compiled.ext.rhs(y, block.address), out[:6])
        assert "CPython" in model.backend_note
    singular = numeric_model(nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2",
                                          ["x*x_dot + y*y_dot"]))
    assert singular.field_function()(np.zeros(4)) == Status.SINGULAR


def test_the_scalar_python_kernels_keep_ieee_arithmetic():
    """W = 2 + log(x) and mu = (1/y, 1) out of their domains: Python's math raises
    there (a ValueError, a ZeroDivisionError: internal errors of the command), C and
    numpy give NaN and inf, which the numeric layer reports. By hand: log(-1) is NaN,
    1/0 is inf."""
    import sympy as sp

    x, y, xd, yd = sp.symbols("x y x_dot y_dot")
    system = nhham.System([x, y], (2 + sp.log(x)) * xd ** 2 / 2 + yd ** 2 / 2,
                          [xd / y + yd])
    kernels = numeric_model(system, backend="numpy").kernels
    W00, W01, W10, W11, mu0, mu1, h = kernels.scalar("geometry", [-1.0, 0.0], [])
    assert np.isnan(W00) and (W01, W10, W11) == (0.0, 0.0, 1.0)
    assert mu0 == np.inf and mu1 == 1.0 and h == 0.0
    W00, *rest = kernels.scalar("geometry", [2.0, 4.0], [])
    assert W00 == pytest.approx(2 + np.log(2.0)) and rest == [0, 0, 1.0, 0.25, 1.0, 0]
    # a parameter slot (here the time) at 0 in 1/t: inf in the batch kernels too
    timed = nhham.System([x], (2 + 1 / sp.Symbol("t")) * xd ** 2 / 2)
    kernels = numeric_model(timed, backend="numpy").kernels
    assert kernels.scalar("geometry", [1.0], [0.0]).tolist() == [np.inf]
    assert kernels.scalar("geometry", [1.0], [0.5]).tolist() == [4.0]
