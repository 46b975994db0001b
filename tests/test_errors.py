"""The exception tree: the key an error is about, and where an empty M_k belongs."""

import doctest

from nhham import errors
from nhham.errors import (
    ComputationError,
    EmptySubmanifoldError,
    InputError,
    RedundantConstraintError,
    UsageError,
    ValidationError,
    key_of,
)


def test_collected_problems_give_the_key_of_the_first():
    error = ValidationError(["nonholonomic_constraints[3]: redundant", "lagrangian: bad"])
    assert error.key == "nonholonomic_constraints[3]"
    assert ValidationError(["no key here"]).key is None
    assert ValidationError(["x: y"], key="parameters").key == "parameters"
    assert InputError("plain message").key is None
    assert UsageError("--atol: must be positive", key="--atol").key == "--atol"


def test_key_paths():
    assert key_of('parameters.m: expected a number') == "parameters.m"
    assert key_of("initial.θ_dot: unknown name") == "initial.θ_dot"
    assert key_of("--max-step: must be positive") == "--max-step"
    assert key_of("/tmp/scene.toml: cannot read") is None


def test_an_empty_submanifold_is_bad_input_and_a_failed_computation():
    """The command exits 2 on it; the constraint algorithm still catches it as the
    ComputationError that marks M_k empty (an inconsistency)."""
    error = EmptySubmanifoldError("could not find points")
    assert isinstance(error, InputError) and isinstance(error, ComputationError)
    assert issubclass(RedundantConstraintError, ValidationError)
    assert "drop_redundant=True" in RedundantConstraintError.ADVICE


def test_docstring_examples():
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE  # as tests/test_examples.py
    assert doctest.testmod(errors, optionflags=flags).failed == 0
