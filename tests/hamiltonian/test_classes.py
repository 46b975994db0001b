"""The result of the first/second-class split (ConstraintClasses): its JSON summary,
repr and LaTeX table."""

import json

import pytest
import sympy as sp

import handmade
from nhham.lagrangian.engine import Policy
from nhham.hamiltonian.classification import classify_constraints


@pytest.mark.parametrize("precision", [None, 30])
def test_to_dict_is_json(precision):
    c = classify_constraints(handmade.sphere_with_knife(),
                             policy=Policy(precision=precision))
    d = json.loads(json.dumps(c.to_dict()))
    assert d["first_class"] == 1 and d["second_class"] == 2
    assert sp.sympify(d["first_class_combinations"][0]).free_symbols


def test_compact_repr_and_latex_of_the_classes():
    from nhham.system.models import rolling_disk

    c = classify_constraints(rolling_disk(symbolic=True))
    assert len(repr(c)) < 200 and "2 first class" in repr(c)
    assert r"\operatorname{rank}" in c._repr_latex_()
