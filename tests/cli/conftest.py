"""Outputs of the ``nhham`` command on the bundled examples, computed once per session.

The command runs in-process (``nhham.cli.main.main``) with stdout and stderr
captured, so the many contract tests share one run per (command, example).
"""

import contextlib
import functools
import io
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
EXAMPLE_NAMES = sorted(p.name for p in EXAMPLES.glob("*.toml"))

# (command, example) pairs left out of the every-example runs, with why: the
# snakeboard's cross-check takes about a minute. The bicycle's cross-check
# takes about half a minute (its linearisation and simulation are checked against the
# benchmark in tests/numerics/test_linearization.py); their forced variants likewise
# (tests/numerics/test_forced_numerics.py).
HEAVY = {("compare", "snakeboard.toml"), ("compare", "whipple_bicycle.toml"),
         ("compare", "snakeboard_gait.toml"), ("compare", "bicycle_steer_control.toml"),
         ("compare", "whipple_bicycle_benchmark.toml"),
         # the same model as whipple_bicycle.toml in other parameters (its linearisation
         # against the closed form: tests/numerics/test_batch_linearization.py)
         ("classify", "whipple_bicycle_benchmark.toml"),
         ("derive", "whipple_bicycle_benchmark.toml")}


def run_fresh(*argv):
    """(exit status, stdout, stderr) of the command in-process, run every time (a test
    that plants something); :func:`run_inprocess` runs each once."""
    from nhham.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main(list(argv))
        except SystemExit as exc:  # argparse
            rc = exc.code
    return rc, out.getvalue(), err.getvalue()


run_inprocess = functools.cache(run_fresh)


def example_args(command, example):
    args = [command, str(EXAMPLES / example), "--json"]
    if command != "classify" and example == "redundant_disk.toml":
        args.append("--drop-redundant")  # its header says so
    return tuple(args)


def envelope_of(command, example):
    """(exit status, envelope, stderr) of ``nhham COMMAND examples/EXAMPLE --json``."""
    rc, out, err = run_inprocess(*example_args(command, example))
    return rc, (json.loads(out) if out.strip() else None), err


def pairs():
    """Every (command, example) the contract tests run, heavy ones excepted."""
    import tomllib

    out = []
    for example in EXAMPLE_NAMES:
        has_initial = "initial" in tomllib.loads((EXAMPLES / example).read_text())
        for command in ("classify", "derive", "compare", "simulate"):
            if command == "simulate" and not has_initial:
                continue
            if (command, example) not in HEAVY:
                out.append((command, example))
    return out


@pytest.fixture(scope="session")
def schema():
    from nhham.render.schema import output_schema

    return output_schema()


def long_expression(terms=300):
    """An expression's text of about 40 characters a term (the bicycle's are thousands)."""
    return " + ".join(f"k{i}*sin(q{i % 7})*(a + b*cos(q{i % 5}))" for i in range(terms))
