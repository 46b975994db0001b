"""A parameter inside sin or cos on a flat M_1: the exceptional conditions that cannot be
evaluated exactly at its value are named in one note that says what to do, and doing it
(the angle declared by its cosine and sine) has them examined."""

import math

import nhham
from nhham.lagrangian.unexamined import trigonometric_parameters, unexamined_notes

L = "m*(x_dot**2 + y_dot**2)/2 + J*theta_dot**2/2 + J*{s}*x_dot*theta_dot"


def _system(params, s):
    return nhham.System(["x", "y", "theta"], L.format(s=s), constraints=["x_dot - y*theta_dot"],
                        parameters=params)


def test_one_note_names_the_conditions_the_parameter_and_the_remedy():
    s = _system({"m": 1.0, "J": 0.5, "alpha": 0.3}, "sin(alpha)")
    assert [p.name for p in trigonometric_parameters(s)] == ["alpha"]
    at = nhham.classification_at_values(s)
    notes = [w for w in at.warnings if "not examined" in w]
    assert len(notes) == 1, at.warnings
    note = notes[0]
    for part in ("det W = 0", "C singular", "first/second-class split",
                 "alpha inside sin or cos", "declare each such angle by its cosine and sine",
                 # cos 0.3 = 0.95533648912..., sin 0.3 = 0.29552020666... (tables)
                 "c_alpha = 0.95533648912", "s_alpha = 0.29552020666",
                 "or accept the verdict as decided"):
        assert part in note, (part, note)
    assert "sin of a number" not in note


def test_the_remedy_has_the_conditions_examined():
    s = _system({"m": 1.0, "J": 0.5, "c_alpha": math.cos(0.3), "s_alpha": math.sin(0.3)},
                "s_alpha")
    at = nhham.classification_at_values(s)
    assert not [w for w in at.warnings if "not examined" in w], at.warnings
    assert trigonometric_parameters(s) == []


def test_other_causes_keep_their_reason_one_note_each():
    s = _system({"m": 1.0, "J": 0.5}, "1")
    notes = unexamined_notes(s, [("sqrt has no exact value", "A"), ("sqrt has no exact value",
                                                                     "B"), ("other", "C")],
                             "not examined")
    assert notes == ["not examined (sqrt has no exact value): whether A; whether B",
                     "not examined (other): whether C"]
