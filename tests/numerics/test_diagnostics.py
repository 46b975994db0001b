"""Diagnostics: what is singular where a run stops (W, the constraints' one-forms, or C),
against matrices written down by hand; and the messages that name it."""

from __future__ import annotations

import math

import numpy as np
import pytest

import nhham
from nhham.numerics.codegen import numeric_model
from nhham.numerics.diagnostics import singularity_at
from nhham.numerics.integrate import simulate

from test_stability import snakeboard, snakeboard_state


def degenerate():
    """L = x^2 x'^2 / 2 + y'^2 / 2, y' = 1: W = diag(x^2, 1) is singular at x = 0, where
    the saddle matrix [[W, mu^T], [mu, 0]] with mu = (0, 1) is singular too."""
    return nhham.System(["x", "y"], "x**2*x_dot**2/2 + y_dot**2/2", ["y_dot - 1"])


def test_singular_W_is_named_with_the_state():
    model = numeric_model(degenerate())
    found = singularity_at(model, [0.0, 0.5, 1.0, 1.0])
    assert found.part == "W" and math.isinf(found.cond_W) and found.where == "x = 0, y = 0.5"
    assert "W = d2L/dv2 is singular" in found.describe() and "x = 0" in found.describe()
    assert singularity_at(model, [1.0, 0.5, 1.0, 1.0]) is None  # W = diag(1, 1), C = -1
    res = simulate(model, (0, 1), [0.0, 0.5, 1.0, 1.0], warn=False)
    assert res.status == -3 and res.singularity.part == "W"
    assert any("cond(W) = inf" in w for w in res.warnings)
    assert "where it stopped, W = d2L/dv2 is singular" in res.describe()


@pytest.mark.parametrize("delta", [0.0, 1e-7])
def test_dependent_one_forms_of_the_snakeboard(delta):
    """At phi = pi/2 - delta the two rows of mu are (by hand)
    (-sin(th + ph), cos(th + ph), -r cos ph, 0, 0) and (-sin(th - ph), cos(th - ph),
    r cos ph, 0, 0): opposite at delta = 0 (rank 1), nearly so for small delta."""
    model = numeric_model(snakeboard())
    y = snakeboard_state(delta)
    th, ph, r = y[2], y[4], 0.5
    mu = np.array([[-math.sin(th + ph), math.cos(th + ph), -r * math.cos(ph), 0, 0],
                   [-math.sin(th - ph), math.cos(th - ph), r * math.cos(ph), 0, 0]])
    s = np.linalg.svd(mu, compute_uv=False)
    found = singularity_at(model, y)
    assert found.part == "mu" and found.m == 2
    if delta == 0.0:
        assert found.rank_mu == 1 and "rank of mu 1 of 2" in found.describe()
    else:
        assert found.rank_mu == 2 and found.cond_mu == pytest.approx(s[0] / s[1], rel=1e-6)
        assert "nearly dependent" in found.describe()
    assert "phi = 1.5708" in found.where


def test_singular_C_with_regular_W_and_mu():
    """L = (x'^2 + y'^2 - z'^2)/2 with y' + z' = 0: W = diag(1, 1, -1), mu = (0, 1, 1),
    C = -mu W^-1 mu^T = -(1 - 1) = 0 everywhere (a free multiplier)."""
    model = numeric_model(nhham.System(["x", "y", "z"], "(x_dot**2 + y_dot**2 - z_dot**2)/2",
                                       ["y_dot + z_dot"]))
    found = singularity_at(model, [0.1, 0.2, 0.3, 1.0, 1.0, -1.0])
    assert found.part == "C" and found.cond_W == pytest.approx(1.0)
    assert found.cond_mu == pytest.approx(1.0) and math.isinf(found.cond_C)
