"""Fuzz tests: whatever text reaches loads_scene, only InputError comes out.

Three generators: arbitrary text, arbitrary TOML documents (random keys and
values, with the scene's own keys over-represented so that deeper layers are
reached), and structurally valid scenes whose expressions are random token
sequences (so that the expression parser and System see hostile input).
"""

from __future__ import annotations

import json
import math
import string

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nhham.errors import InputError
from nhham.system.expressions import FUNCTIONS
from nhham.system.scene import Scene, loads_scene

FUZZ = settings(max_examples=200, deadline=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


def load_or_input_error(text: str):
    """Load ``text``; any exception other than an InputError fails the test."""
    try:
        scene = loads_scene(text, source="fuzz.toml")
    except InputError as exc:
        assert str(exc)  # every error explains itself
        return None
    assert isinstance(scene, Scene)
    return scene


# ------------------------------------------------------------ plain text
@FUZZ
@given(st.text(max_size=300))
def test_random_text(text):
    load_or_input_error(text)


_scene_lines = st.sampled_from([
    'coordinates = ["x", "y"]', 'lagrangian = "x_dot**2/2 + y_dot**2/2"', "[initial]",
    "[simulate]", "x = 0.0", "x_dot = 1.0", "y = 1", "y_dot = nan", 'constraints = ["x_dot - y"]',
    "parameters = { m = 1.0 }", 'holonomic = ["x"]', "t_end = inf", '"', "[", "=", "",
    'lagrangian = """', '"""', "# comment", 'method = "RK45"', "rtol = -1",
])


@FUZZ
@given(st.lists(_scene_lines, max_size=15))
def test_random_lines(lines):
    load_or_input_error("\n".join(lines))


# -------------------------------------------------- random TOML documents
def toml_value(value) -> str:
    """Serialize a generated value as an inline TOML value."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)  # JSON escapes are valid in TOML basic strings
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(v)}" for k, v in value.items()) + "}"


_KEYS = ["name", "description", "coordinates", "parameters", "symbolic_parameters",
         "lagrangian", "constraints", "holonomic", "initial", "simulate",
         "x", "y", "x_dot", "y_dot", "m", "t_end", "method", "rtol", "step"]
_key = st.one_of(st.sampled_from(_KEYS), st.text(min_size=1, max_size=8))
_scalar = st.one_of(
    st.booleans(), st.integers(-10**20, 10**20), st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from(["x", "y", "x_dot", "m", "x_dot**2/2", "sin(x)", "1/0", "__import__", "", "lambda"]),
    st.text(max_size=10),
)
_value = st.recursive(
    _scalar,
    lambda children: st.one_of(st.lists(children, max_size=4),
                               st.dictionaries(_key, children, max_size=4)),
    max_leaves=10,
)


@FUZZ
@given(st.dictionaries(_key, _value, max_size=10))
def test_random_toml_documents(document):
    text = "\n".join(f"{json.dumps(k)} = {toml_value(v)}" for k, v in document.items())
    load_or_input_error(text)


# --------------------------------------- valid structure, random expressions
_tokens = st.sampled_from(
    ["x", "y", "x_dot", "y_dot", "m", "k", "lambda", "I", "E", "pi"] + list(FUNCTIONS)
    + ["(", ")", "+", "-", "*", "/", "**", ",", "0", "1", "2", "0.5", "1e308", "1e-308", "1000",
       "10", ".", "[", "]", "'", ":", "__import__", "__class__", "if", "else", "for", "in", "==",
       "1j", "@", "%", "not", "\n", "#", "f'", "{", "}", "**-"]
)
_expression = st.lists(_tokens, min_size=1, max_size=14).map(" ".join)
# Mostly well-formed pieces so that System's checks are reached too.
_reasonable = st.sampled_from(
    ["x_dot**2/2 + y_dot**2/2", "m*x_dot**2/2 + y_dot**2 - k*x**2", "x_dot - y*y_dot",
     "x_dot**2", "x_dot*y_dot", "sin(x)*x_dot + cos(x)*y_dot", "x", "x**2 + y**2 - 1",
     "x_dot", "lambda*y_dot + x_dot", "0", "1", "x_dot/x", "exp(x)*y_dot - x_dot"]
)
_expr = st.one_of(_expression, _reasonable)


@FUZZ
@given(
    lagrangian=_expr,
    constraints=st.lists(_expr, max_size=3),
    holonomic=st.lists(_expr, max_size=2),
    values=st.fixed_dictionaries({}, optional={
        "m": st.floats(allow_nan=True, allow_infinity=True),
        "k": st.floats(-10, 10),
        "lambda": st.floats(-10, 10),
    }),
    initial=st.one_of(st.none(), st.fixed_dictionaries(
        {name: st.floats(-3, 3) for name in ["x", "y", "x_dot", "y_dot"]})),
)
def test_random_expressions_in_valid_scenes(lagrangian, constraints, holonomic, values, initial):
    symbolic = [p for p in ["m", "k", "lambda"] if p not in values]
    lines = [
        'coordinates = ["x", "y"]',
        f"parameters = {toml_value(values)}",
        f"symbolic_parameters = {toml_value(symbolic)}",
        f"lagrangian = {json.dumps(lagrangian)}",
        f"constraints = {toml_value(constraints)}",
        f"holonomic = {toml_value(holonomic)}",
    ]
    if initial is not None:
        lines.append("[initial]")
        lines.extend(f"{k} = {toml_value(v)}" for k, v in initial.items())
    load_or_input_error("\n".join(lines))


@FUZZ
@given(st.text(alphabet=string.ascii_letters + string.digits + "_.-\"' []{}=#\n", max_size=200))
def test_random_toml_like_text(text):
    load_or_input_error(text)
