"""The verdict at the scene's parameter values (nhham.verdict.values), against cases
derived by hand: the values on an exceptional set get that case's verdict, values near one
a warning with the distance computed by hand."""

from __future__ import annotations

import sympy as sp

import nhham
from nhham.lagrangian.linalg import FLOAT64
from nhham.verdict.values import classification_at_values
from parametric_systems import key, two_bodies


def test_issue_example_says_singular_at_b_equal_one():
    """L = (a q1'^2 + q2'^2 - q3'^2)/2, phi = q2' + b q3', C = -(1 - b^2): zero at b = 1."""
    S = nhham.System(["q1", "q2", "q3"], "(a*q1_dot**2 + q2_dot**2 - q3_dot**2)/2",
                     ["q2_dot + b*q3_dot"], parameters={"a": 1.0, "b": 1.0})
    at = classification_at_values(S)
    assert key(at.verdict)[:5] == ("underdetermined", False, 0, 1, 1)
    assert [str(c) for c in at.conditions] == ["b - 1"]
    assert at.differs and at.generic.regular and at.generic.rank_C == 1
    assert at.system.constraints == (sp.Symbol("q2_dot") + sp.Symbol("q3_dot"),)
    # generic values: the generic verdict, nothing substituted
    S2 = nhham.System(S.coordinates, S.lagrangian, S.constraints,
                      parameters={"a": 1.0, "b": 0.5})
    at2 = classification_at_values(S2)
    assert at2.conditions == () and not at2.differs and at2.verdict.rank_C == 1


def test_values_on_a_two_parameter_condition_keep_the_names():
    at = classification_at_values(two_bodies({"I1": 0.5, "I2": 0.5, "k": 2.0}))
    assert key(at.verdict) == ("determined", False, 0, 3, 0, True, 1, 2)
    assert [str(c) for c in at.conditions] == ["I1 - I2"]
    assert sp.Symbol("I2") in at.system.lagrangian.free_symbols
    at0 = classification_at_values(two_bodies({"I1": 0.5, "I2": 0.5, "k": 0.0}))
    assert key(at0.verdict)[:5] == ("underdetermined", False, 0, 1, 1)


def shift_fields(monkeypatch) -> list:
    """The fields the nearness estimates are made in, appended as they are used."""
    from nhham.lagrangian import exceptional

    fields = []
    original = exceptional.ExceptionalData._with_shifts

    def spy(self, fn, base, values, K=sp.QQ):
        fields.append(K)
        return original(self, fn, base, values, K)

    monkeypatch.setattr(exceptional.ExceptionalData, "_with_shifts", spy)
    return fields


def test_values_near_an_exceptional_set_are_warned_about(monkeypatch):
    """By hand: C is singular on the plane I1 = I2. The smallest change of the parameters,
    each relative to its own value, that reaches it from (I1, I2, k) = (0.5, 0.5 + 1e-10, 2)
    is, to first order, |I1 - I2| / sqrt(I1^2 + I2^2) = 1e-10 / 0.7071 = 1.4e-10.
    float64 finds the values near and the estimate is made again in 200-bit; for far
    values float64 is enough."""
    from nhham.lagrangian import exceptional

    fields = shift_fields(monkeypatch)
    near = classification_at_values(two_bodies({"I1": 0.5, "I2": 0.5 + 1e-10, "k": 2.0}))
    assert near.conditions == () and near.verdict.regular
    (warning,) = near.warnings
    assert "relative distance 1.4e-10" in warning and "C singular" in warning
    assert exceptional.SHIFT_FIELD in fields and FLOAT64 in fields
    fields.clear()
    far = classification_at_values(two_bodies({"I1": 0.5, "I2": 0.7, "k": 2.0}))
    assert far.warnings == ()
    assert FLOAT64 in fields and exceptional.SHIFT_FIELD not in fields


def test_values_far_from_every_exceptional_set_raise_no_warning(monkeypatch):
    """The 4-link snake at m = l = 1: every datum is nonzero modulo p at the values (a
    proof, so none is evaluated over Q) and none is near vanishing -- in particular
    the antisymmetric bracket matrix, whose determinant is estimated in floating point
    at moved values. float64 puts each far beyond the margin, so 200-bit is not used."""
    from nhham import models

    fields = shift_fields(monkeypatch)
    at = classification_at_values(models.snake(4))
    assert at.conditions == () and at.warnings == ()
    assert at.verdict.second_class == 4
    assert len(fields) == 5 and set(fields) == {FLOAT64}


def test_an_angle_within_rounding_of_pi_over_2_is_named():
    """alpha = 1.5707963267948966 (the shortest decimal of the double nearest pi/2)
    inside sin and cos: answered at that decimal (1.9e-17 from pi/2: cos(alpha) is not 0
    there), and a warning says how close to pi/2 it is; at alpha = 0.3 nothing is said."""
    import nhham
    from nhham.verdict.values import classification_at_values

    def incline(alpha):
        return nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2 - g*cos(alpha)*x",
                            ["x_dot - sin(alpha)*y_dot"],
                            parameters={"g": 9.81, "alpha": alpha})

    near = classification_at_values(incline(1.5707963267948966)).warnings
    assert any("alpha = 1.5707963267948966 is within 1.9e-17 of 1*pi/2, where cos(alpha)"
               in w for w in near)
    assert len(near) == 1  # every decision taken at points with the values: nothing else
    assert not any("pi/2" in w for w in classification_at_values(incline(0.3)).warnings)


def test_the_distance_to_an_exceptional_set_is_free_of_units():
    """The sleigh's C = -(1/m + a^2/I) is -1 at m = 1e30 kg (cond C = 1): no warning (the
    distance divided by |values| put it at 2.5e-31); and the same values in grams and
    centimetres are as far as in kilograms and metres."""
    from nhham import load_scene

    heavy = load_scene("examples/chaplygin_sleigh.toml", values={"m": 1e30})
    assert classification_at_values(heavy.system).warnings == ()
    near = {"I1": 0.5, "I2": 0.5 + 1e-10, "k": 2.0}
    scaled = {"I1": 0.5e7, "I2": (0.5 + 1e-10) * 1e7, "k": 2.0 * 1e3}   # g cm^2, g
    warning, = classification_at_values(two_bodies(near)).warnings
    again, = classification_at_values(two_bodies(scaled)).warnings
    assert "relative distance 1.4e-10" in warning and "relative distance 1.4e-10" in again
