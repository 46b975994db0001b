"""Two compiled models in one process each call their own code.

A model's library is also a CPython extension module. Loaded under one module name for
every library, the second load of a library (another model of the same system) refilled
the module of that name, the last other library loaded, with the first library's
functions: that model's hot path then ran another system's code on its parameter block
(a roller racer's accelerations from a from_mechanics copy of its scene came out wrong
after the scene was loaded twice; tests/numerics/test_roller_racer.py). Expected values:
the sleigh's accelerations by hand.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import nhham
from nhham.numerics.codegen import c_compiler, numeric_model


def sleigh(order):
    """The Chaplygin sleigh (m, I, a), its parameters listed in ``order``: the same
    equations, another parameter layout (another library)."""
    x, y, th = sp.symbols("x y theta")
    xd, yd, thd = sp.symbols("x_dot y_dot theta_dot")
    m, I, a = sp.symbols("m I a")
    L = m * (xd**2 + yd**2) / 2 + I * thd**2 / 2
    values = {"m": 1.0, "I": 0.25, "a": 0.5}
    return nhham.System(["x", "y", "theta"], L,
                        [-a * thd - sp.sin(th) * xd + sp.cos(th) * yd],
                        parameters={k: values[k] for k in order}, name="sleigh")


def by_hand(y, m=1.0, I=0.25, a=0.5):
    """(x'', y'', theta'') of the sleigh: G' = u e1 + v e2 with v = a w on M_1 (the blade
    at G - a e1 does not slide sideways), the blade's force f e2 there: m (u' - v w) = 0,
    m (v' + u w) = f, I w' = -a f, so w' = -m a u w / (I + m a^2) and
    G'' = (a w' + u w) e2."""
    th, xd, yd, w = y[2], y[3], y[4], y[5]
    u = np.cos(th) * xd + np.sin(th) * yd
    wd = -m * a * u * w / (I + m * a**2)
    return np.array([*((a * wd + u * w) * np.array([-np.sin(th), np.cos(th)])), wd])


@pytest.mark.skipif(not c_compiler(), reason="no C compiler")
def test_each_model_calls_its_own_library():
    first = numeric_model(sleigh(("m", "I", "a")))
    other = numeric_model(sleigh(("a", "m", "I")))
    again = numeric_model(sleigh(("m", "I", "a")))   # the first library loaded once more
    th, u, w = 0.3, 0.4, 1.5          # G' = u e1 + a w e2 (on M_1)
    y = np.array([0.0, 0.0, th, u * np.cos(th) - 0.5 * w * np.sin(th),
                  u * np.sin(th) + 0.5 * w * np.cos(th), w])
    want = by_hand(y)
    for model in (first, other, again):
        assert model.backend == "c"
        np.testing.assert_allclose(model.rhs(0.0, y)[3:], want, rtol=0, atol=1e-13)
