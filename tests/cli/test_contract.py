"""The JSON contract: one envelope, one schema, one type per key, expressions that read back.

Every example runs through classify, derive, compare and simulate (bench on
one scene: it is a minute of work per scene); each output is checked against
the JSON Schema shipped in the package, and every expression in it is read
back with ``nhham.parse_expression`` and the names the envelope lists.
"""

import json
import re

import jsonschema
import pytest
import sympy as sp

import nhham
from nhham.system.expressions import to_text

from conftest import EXAMPLE_NAMES, EXAMPLES, envelope_of, pairs, run_inprocess

SNAKE = re.compile(r"^[a-z][a-z0-9_]*$")
COMMANDS = ("classify", "derive", "compare", "simulate", "bench")


@pytest.fixture(scope="module")
def bench_envelope():
    rc, out, err = run_inprocess("bench", str(EXAMPLES / "chaplygin_sleigh.toml"), "--quick",
                                 "--json")
    assert rc == 0, err
    return json.loads(out)


def all_envelopes(extra=()):
    for command, example in pairs():
        rc, env, err = envelope_of(command, example)
        yield command, example, rc, env, err
    for env in extra:
        yield env["command"], "chaplygin_sleigh.toml", 0, env, ""


@pytest.mark.parametrize("command,example", pairs())
def test_every_example_output_matches_the_schema(command, example, schema):
    rc, env, err = envelope_of(command, example)
    # 0, or 3 for a simulation that stopped early (then the envelope says why).
    assert rc in (0, 3), err
    assert env is not None, err
    jsonschema.validate(env, schema)
    assert env["command"] == command and env["nhham_version"] == nhham.__version__
    assert env["scene"]["path"].endswith(example)
    if rc == 3:
        assert command == "simulate" and env["result"]["success"] is False
        assert err.strip().splitlines()[-1].startswith("nhham: simulation stopped")
        assert env["error"]["kind"] == "failed"
        assert err.strip().splitlines()[-1] == f"nhham: {env['error']['message']}"
    else:
        assert env["error"] is None


def test_bench_output_matches_the_schema(bench_envelope, schema):
    jsonschema.validate(bench_envelope, schema)
    rows = bench_envelope["result"]["rows"]
    assert {"DOP853", "rattle"} <= {r["method"] for r in rows}
    for r in rows:
        assert r["error"] is None or r["error"] >= 0
    # RATTLE keeps the constraint to round-off at every step
    assert max(r["constraint_residual"] for r in rows if r["method"] == "rattle") < 1e-12


def test_the_schema_is_a_valid_draft_2020_12_schema(schema):
    jsonschema.Draft202012Validator.check_schema(schema)
    # ... and it names a result schema for every command of the CLI
    from nhham.cli.main import COMMANDS as CLI

    for name in CLI:
        assert name in schema["$defs"], name


def test_the_schema_rejects_what_it_should(schema):
    """The schema is not vacuous: a wrong type, a missing key, a stray key fail."""
    rc, env, _ = envelope_of("classify", "rolling_disk.toml")
    bad = [json.loads(json.dumps(env)) for _ in range(9)]
    bad[0]["result"]["status"] = 0
    del bad[1]["result"]["rank_c"]
    bad[2]["extra"] = 1
    bad[3]["warnings"] = ["two\nlines"]
    del bad[4]["error"]
    bad[5]["result"] = None  # no result needs an error
    bad[6]["error"] = {"kind": "usage", "message": "m", "key": None}  # ... and then no result
    bad[7]["error"] = {"kind": "oops", "message": "m", "key": None}
    bad[8]["result"], bad[8]["error"] = None, {"kind": "input", "message": "m"}  # key missing
    for b in bad:
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(b, schema)


def _walk(value, path=()):
    if isinstance(value, dict):
        for k, v in value.items():
            yield path + (k,), k, v
            yield from _walk(v, path + (k,))
    elif isinstance(value, list):
        for v in value:
            yield from _walk(v, path + ("[]",))


def _json_type(v):
    if v is None:
        return None
    if isinstance(v, bool):
        return "boolean"
    if isinstance(v, (int, float)):
        return "number"
    return type(v).__name__


def test_keys_are_snake_case_with_one_type_across_commands(bench_envelope):
    """Every key anywhere in any output is snake_case and has one JSON type
    (null allowed beside it) in every command; settings are free-form. The envelope's
    own keys form their own namespace: its ``error`` (null, or the failure's
    ``{kind, message, key}``) is not the ``error`` of a bench row (a number)."""
    seen = {}
    for command, example, rc, env, err in all_envelopes([bench_envelope]):
        for path, key, value in _walk(env):
            if "settings" in path[:-1]:
                continue
            assert SNAKE.match(key), (command, example, path)
            t = _json_type(value)
            if t is not None:
                name = f"envelope.{key}" if len(path) == 1 else key
                seen.setdefault(name, {}).setdefault(t, (command, example, path))
    clashes = {k: v for k, v in seen.items() if len(v) > 1}
    assert not clashes, clashes


# Where expressions are, per command (paths into the result).
def _expressions(command, result):
    if command == "classify":
        for s in result["stages"]:
            yield from s["constraints"]
        yield from result["final_constraints"]
        yield from result["first_class_combinations"]
    elif command == "derive":
        yield from result["field"] or ()
        yield from result["multipliers"] or ()
        for row in (result["constraint_matrix"] or []) + result["mass_matrix"] + \
                result["constraint_jacobian"]:
            yield from row
        yield from result["forcing"]
        yield from result["constraint_rhs"]
        yield from result.get("secondary_constraints", ())
        yield result["energy"]
    elif command == "compare":
        d = result["dirac_vs_projected"]
        if d is not None and d["difference"] is not None:
            yield from d["difference"]


def _same_values(a, b, points=1):
    """a == b at a seeded random point (values in [0.3, 1.3]: no singular denominators)."""
    import random

    rng = random.Random(1)
    syms = sorted(a.free_symbols | b.free_symbols, key=str)
    for _ in range(points):
        # numbers put in first, then one evaluation: evalf(subs=) walks a bicycle's
        # expressions for tens of seconds
        at = {s: sp.Float(rng.uniform(0.3, 1.3), 30) for s in syms}
        va, vb = (complex(e.xreplace(at).evalf(30)) for e in (a, b))
        if abs(va - vb) > 1e-9 * (1 + abs(va)):
            return False
    return True


def test_every_expression_reads_back_with_the_scene_names():
    """parse_expression(text, scene.names) reads every expression; printing it again
    gives the same text (one printer), and no name turns into a sympy constant."""
    count = 0
    for command, example, rc, env, err in all_envelopes():
        names = env["scene"]["names"]
        symbols = {sp.Symbol(n) for n in names}
        for text in _expressions(command, env["result"]):
            expr = nhham.parse_expression(text, names)
            assert expr.free_symbols <= symbols, (example, text)
            assert not expr.has(sp.I, sp.E, sp.S.Exp1), (example, text)
            # One printer: printing what was read and reading it again gives the same
            # function (the text may differ: "-(a + b)*c" reads as (-a - b)*c).
            again = nhham.parse_expression(to_text(expr), names)
            assert again == expr or _same_values(expr, again), (example, text)
            count += 1
    assert count > 250


def test_sleigh_parameter_I_is_read_as_a_parameter():
    """The sleigh's first-class constraint on T*Q is its only constraint phi with
    x' = p_x/m, y' = p_y/m, theta' = p_theta/I (L = m(x'^2 + y'^2)/2 + I theta'^2/2):
    -sin(theta) p_x/m + cos(theta) p_y/m - a p_theta/I, up to a nonzero factor."""
    rc, env, _ = envelope_of("classify", "chaplygin_sleigh.toml")
    (text,) = env["result"]["first_class_combinations"]
    assert "I" in re.findall(r"[A-Za-z_]\w*", text)
    g = nhham.parse_expression(text, env["scene"]["names"])
    x, y, th, px, py, pth, m, I, a = sp.symbols("x y theta p_x p_y p_theta m I a")
    expected = -sp.sin(th) * px / m + sp.cos(th) * py / m - a * pth / I
    ratio = sp.simplify(g / expected)
    assert ratio.free_symbols == set() and ratio != 0
    # sympify would have read I as the imaginary unit:
    assert sp.sympify(text).has(sp.I)


@pytest.mark.parametrize("example", EXAMPLE_NAMES)
def test_scene_expressions_round_trip(example):
    """to_text -> parse_expression gives back the very expressions of the system."""
    scene = nhham.load_scene(EXAMPLES / example, drop_redundant=True)
    s = scene.system
    names = [q.name for q in s.coordinates] + [v.name for v in s.velocities] + \
        [p.name for p in s.parameters]
    for expr in (s.lagrangian, *s.constraints, *s.holonomic):
        assert nhham.parse_expression(to_text(expr), names) == expr


@pytest.mark.parametrize("example", ["rolling_disk.toml", "paper_3_1.toml",
                                     "pendulum_cartesian.toml"])
def test_hamiltonian_derive_matches_the_schema(example, schema):
    rc, out, err = run_inprocess("derive", str(EXAMPLES / example), "--side", "hamiltonian",
                                 "--json")
    assert rc == 0, err
    env = json.loads(out)
    jsonschema.validate(env, schema)
    r = env["result"]
    assert r["side"] == "hamiltonian" and r["form"] == "explicit" and r["mass_matrix"] is None


def test_hamiltonian_derive_of_a_singular_c_leaves_the_multiplier_free():
    """Example 3.1 by hand: H = (p1^2 + p2^2 - p3^2)/2, phi^H = p2 - p3, C^H = 0 and
    X_H(phi^H) = 0, so dp/dt = -lambda_1 (0, 1, 1) with lambda_1 free."""
    rc, out, err = run_inprocess("derive", str(EXAMPLES / "paper_3_1.toml"), "--side",
                                 "hamiltonian", "--json")
    assert rc == 0, err
    r = json.loads(out)["result"]
    assert r["free_multiplier_symbols"] == ["lambda_1"]
    got = [sp.sympify(f) for f in r["field"]]
    p1, p2, p3, lam = sp.symbols("p_q1 p_q2 p_q3 lambda_1")
    assert got == [p1, p2, -p3, 0, -lam, -lam]
