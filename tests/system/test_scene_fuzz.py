"""Fuzz tests: whatever text reaches loads_scene, only InputError comes out.

Three generators: arbitrary text, arbitrary TOML documents (random keys and
values, with the scene's own keys over-represented so that deeper layers are
reached), and structurally valid scenes whose expressions are random token
sequences (so that the expression parser and System see hostile input).
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import re
import string
import tempfile
from dataclasses import dataclass
from pathlib import Path

from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from nhham.cli.main import main
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


# ------------------------------------------ well-formed scenes through the command
# Scenes every reader accepts (names known, expressions well formed), built from the
# pieces a mechanical system has: a kinetic energy with random coefficients, a potential,
# sometimes a term not quadratic in v, constraints affine or not, holonomic ones, the
# time t, parameters with values, [initial], [steady]; and a command with its options.
# Whatever is drawn, the command ends in 0, 2 (bad input, one line naming it) or
# 3 (did not succeed, one line saying why): never 1, an internal failure.
_COORDINATES = ["x", "y", "z", "q1", "q2", "theta"]
_PARAMETERS = ["m", "k", "a"]
_UNARY = sorted(set(FUNCTIONS) - {"atan2"})
_CONSTANTS = ["1", "2", "3", "1/2", "0.5", "pi"]


def _expressions(atoms, depth: int):
    """Expressions in ``atoms`` (names) of nesting at most ``depth``: the functions of the
    scene reader's table, + - * /, integer and rational powers."""
    leaf = st.sampled_from(list(atoms) + _CONSTANTS)
    if depth == 0:
        return leaf
    sub = _expressions(atoms, depth - 1)
    return st.one_of(
        leaf,
        st.builds("{}({})".format, st.sampled_from(_UNARY), sub),
        st.builds("atan2({}, {})".format, sub, sub),
        st.builds("({}) {} ({})".format, sub, st.sampled_from(["+", "-", "*", "/"]), sub),
        st.builds("({})**{}".format, sub, st.sampled_from(["2", "3", "-1", "-2", "(1/2)"])),
    )


def _coefficient(q_expr, parameters):
    """A coefficient of the kinetic energy: 1, a parameter, positive or random in q."""
    return st.one_of(
        st.just("1"),
        st.sampled_from(parameters or ["2"]),
        q_expr.map("(1 + ({})**2)".format),
        q_expr.map("exp({})".format),
        q_expr,
    )


@st.composite
def _lagrangian(draw, coordinates, q_expr, qv_expr, parameters):
    velocities = [f"{c}_dot" for c in coordinates]
    terms = [f"{draw(_coefficient(q_expr, parameters))}*{v}**2/2" for v in velocities]
    if len(velocities) > 1 and draw(st.booleans()):   # a cross term
        i, j = draw(st.permutations(range(len(velocities))))[:2]
        terms.append(f"({draw(q_expr)})*{velocities[i]}*{velocities[j]}/4")
    if draw(st.booleans()):                            # gyroscopic: linear in v
        terms.append(f"({draw(q_expr)})*{draw(st.sampled_from(velocities))}")
    if draw(st.booleans()):                            # a potential
        terms.append(f"-({draw(q_expr)})")
    if draw(st.integers(0, 3)) == 0:                   # not quadratic in v
        terms.append(draw(st.one_of(
            st.sampled_from(velocities).map("{}**4/12".format), qv_expr)))
    return " + ".join(terms)


@st.composite
def _constraint(draw, coordinates, q_expr, qv_expr):
    velocities = [f"{c}_dot" for c in coordinates]
    if draw(st.integers(0, 3)) == 0:                   # nonlinear in v (Chetaev)
        return draw(qv_expr)
    chosen = draw(st.lists(st.sampled_from(velocities), min_size=1, unique=True))
    terms = [f"({draw(q_expr)})*{v}" if draw(st.booleans()) else v for v in chosen]
    if draw(st.booleans()):                            # affine: h(q, t)
        terms.append(f"({draw(q_expr)})")
    return " + ".join(terms)


_values = st.one_of(st.integers(-3, 3).map(float),
                    st.floats(-3, 3, allow_nan=False).map(lambda x: round(x, 3)))


@dataclass(frozen=True)
class SceneCase:
    """A drawn scene (TOML text) and the command line to run on it (without the file)."""

    text: str
    argv: tuple

    def __str__(self):  # what Hypothesis prints of a failing example
        return f"nhham {' '.join(self.argv)} SCENE with SCENE =\n{self.text}"


def _using(expressions, names):
    """``expressions`` made to use one of ``names`` (a whole word: ``x`` is not in ``exp``):
    one that uses none is multiplied by one of them (no filter: most draws would fail it)."""
    uses = re.compile(r"\b(" + "|".join(map(re.escape, names)) + r")\b").search
    return st.tuples(expressions, st.sampled_from(names)).map(
        lambda pair: pair[0] if uses(pair[0]) else f"({pair[0]})*{pair[1]}")


@st.composite
def well_formed_scenes(draw, budget: float = 2.0) -> SceneCase:
    """A well-formed scene and a command line (classify, derive, compare, simulate,
    linearize, which gets a [steady] table) with ``--budget`` ``budget`` (seconds), so
    that a hard case ends in exit 3, not a hang.

    Drawn to reach the computations more often than the reader's refusals: as many
    constraints as velocities only now and then, constraints and holonomic ones that
    use the velocities and coordinates, an [initial] table for simulate giving the
    coordinates; the refusals are still drawn (a parameter of value 0, 1/q on M_1, ...).
    """
    command = draw(st.sampled_from(["classify", "derive", "compare", "simulate", "linearize"]))
    coordinates = draw(st.lists(st.sampled_from(_COORDINATES), min_size=1, max_size=3,
                                unique=True))
    n = len(coordinates)
    velocities = [f"{c}_dot" for c in coordinates]
    parameters = draw(st.lists(st.sampled_from(_PARAMETERS), max_size=2, unique=True))
    time = ["t"] if draw(st.booleans()) else []
    depth = draw(st.integers(0, 2))
    q_expr = _expressions(coordinates + parameters + time, depth)
    qv_expr = _expressions(coordinates + velocities + parameters + time, depth)
    values = {p: draw(st.one_of(_values, st.sampled_from([1.0, 2.0, 0.5]))) for p in parameters}
    holonomic = []
    if n > 1 and draw(st.integers(0, 3)) == 0:
        holonomic = [draw(_using(q_expr, coordinates))]
    room = n - len(holonomic) - (0 if draw(st.integers(0, 9)) == 0 else 1)
    constraint = _constraint(coordinates, q_expr, _using(qv_expr, velocities))
    constraints = draw(st.lists(constraint, max_size=max(room, 0)))
    lines = [f"coordinates = {toml_value(coordinates)}",
             f"parameters = {toml_value(values)}",
             "lagrangian = " + json.dumps(draw(_lagrangian(coordinates, q_expr, qv_expr,
                                                           parameters))),
             f"constraints = {toml_value(constraints)}",
             f"holonomic = {toml_value(holonomic)}"]
    state = coordinates + velocities
    if draw(st.integers(0, 9)) < (9 if command == "simulate" else 3):
        if draw(st.integers(0, 3)):  # a value left out per constraint, solved by nhham
            left_out = (draw(st.permutations(velocities))[:len(constraints) + len(holonomic)]
                        + draw(st.permutations(coordinates))[:len(holonomic)])
            given = [name for name in state if name not in left_out]
        else:                        # any: what is missing or too much is refused
            given = draw(st.lists(st.sampled_from(state), unique=True))
        lines += ["[initial]"] + [f"{name} = {draw(_values)!r}" for name in given]
    if command == "linearize" or draw(st.integers(0, 9)) == 0:
        lines += ["[steady]"] + [f"{name} = {draw(_values)!r}" for name in state]
    argv = [command, "--budget", f"{budget:g}"]
    if draw(st.booleans()):
        argv.append("--json")
    if command == "classify" and draw(st.integers(0, 4)) == 0:
        argv.append("--parametric")
    if command == "derive":
        argv += draw(st.sampled_from([[], ["--side", "hamiltonian"], ["--explicit"]]))
    if command == "simulate":
        argv += ["--t-end", repr(draw(st.sampled_from([0.1, 0.5, 1.0])))]
        argv += draw(st.sampled_from(
            [[], ["--projection"], ["--project-initial"]]
            + [["--method", m] for m in ("RK45", "RK23", "Radau", "BDF", "LSODA", "reference")]
            + [["--method", m, "--step", "0.05"] for m in ("rk4", "rattle", "rattle4")]))
    return SceneCase("\n".join(lines) + "\n", tuple(argv))


def run_command(case: SceneCase, folder: Path) -> tuple[int, str, str]:
    """Run the case's command in this process: (exit status, stdout, stderr)."""
    scene = folder / "scene.toml"
    scene.write_text(case.text, encoding="utf-8")
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([*case.argv, str(scene)])
    return status, out.getvalue(), err.getvalue()


def check_outcome(case: SceneCase, status: int, out: str, err: str) -> None:
    """0, 2 or 3; a failure says in one line what is wrong (or why it did not succeed)."""
    assert status in (0, 2, 3), f"exit {status}: {err.strip()}\n{case}"
    if status == 0:
        return
    last = err.strip().splitlines()[-1] if err.strip() else ""
    assert last.startswith("nhham: ") and "Traceback" not in err, f"{err}\n{case}"
    if "--json" in case.argv:  # the same line in the envelope's error
        message = json.loads(out)["error"]["message"]
        assert message.strip() and "\n" not in message, case


# The suite's share (a few hundred examples, each command bounded by half a second); the
# big runs: NHHAM_FUZZ_EXAMPLES=10000 here (stops at the first failure), or
# bench/scene_fuzz.py (counts them all, two seconds a command).
FUZZ_EXAMPLES = int(os.environ.get("NHHAM_FUZZ_EXAMPLES", "200"))
FUZZ_BUDGET = float(os.environ.get("NHHAM_FUZZ_BUDGET", "0.5"))


@settings(max_examples=FUZZ_EXAMPLES, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much,
                                 HealthCheck.data_too_large])
@given(well_formed_scenes(budget=FUZZ_BUDGET))
def test_well_formed_scenes_end_in_0_2_or_3(case):
    with tempfile.TemporaryDirectory() as folder:
        status, out, err = run_command(case, Path(folder))
    event(f"{case.argv[0]}: exit {status}")
    check_outcome(case, status, out, err)
