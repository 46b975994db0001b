"""The options every entry point shares (nhham.settings): one rule each, one error.

A library call given an option out of its range raises InputError naming the function and
the option (key), as the command does for its flags; nothing is silently changed.
"""

import doctest

import pytest

import nhham
from nhham import settings
from nhham.errors import InputError

DISK = nhham.models.rolling_disk()

CALLS = {
    "analyze_constraints": lambda **kw: nhham.analyze_constraints(DISK, **kw),
    "classify_constraints": lambda **kw: nhham.classify_constraints(DISK, **kw),
    "cross_check": lambda **kw: nhham.cross_check(DISK, **kw),
    "dirac_vs_projected": lambda **kw: nhham.dirac_vs_projected(DISK, **kw),
    "lagrangian_geometry": lambda **kw: nhham.lagrangian_geometry(DISK, **kw),
    "hamiltonian_side": lambda **kw: nhham.hamiltonian_side(DISK, **kw),
    "classification_at_values": lambda **kw: nhham.classification_at_values(DISK, **kw),
    "parametric_classification": lambda **kw: nhham.parametric_classification(DISK, **kw),
}

BAD = [
    ("analyze_constraints", "precision", 8),
    ("analyze_constraints", "precision", "30"),
    ("analyze_constraints", "samples", 0),
    ("analyze_constraints", "max_stages", 0),
    ("analyze_constraints", "seed", 1.5),
    ("analyze_constraints", "seed", -1),   # numpy's generators refuse it (was exit 1)
    ("classify_constraints", "samples", -3),
    ("classify_constraints", "tol", -1.0),
    ("classify_constraints", "tol", float("nan")),
    ("cross_check", "precision", 2),
    ("cross_check", "samples", 10**6),
    ("dirac_vs_projected", "samples", 0),
    ("lagrangian_geometry", "precision", 0),
    ("hamiltonian_side", "seed", True),
    ("classification_at_values", "near", -1.0),
    ("classification_at_values", "max_depth", -1),
    ("parametric_classification", "points", 0),
    ("parametric_classification", "max_depth", 1.5),
]


@pytest.mark.parametrize("where, key, value", BAD)
def test_an_option_out_of_range_is_named(where, key, value):
    with pytest.raises(InputError) as info:
        CALLS[where](**{key: value})
    assert info.value.key == key
    assert str(info.value).startswith(f"{where}: {key}: expected")


def test_options_in_range_are_taken():
    assert nhham.analyze_constraints(DISK, policy=nhham.Policy(precision=30, samples=4, seed=3),
                                     max_stages=2).status == "determined"
    for key, value in [("precision", None), ("precision", 16), ("samples", 1),
                       ("tol", None), ("tol", 1e-3), ("near", 0), ("max_depth", 0),
                       ("points", 1), ("max_stages", None), ("seed", 0)]:
        assert settings.option_problem(key, value) is None, (key, value)


def test_the_rules_read_as_documented():
    assert doctest.testmod(settings).failed == 0
