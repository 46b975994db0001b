"""A change of units does not change a verdict: every parameter of an example scaled by
1e-12 or 1e12 (the verdicts of these systems hold for all positive values: by hand, C is
-mu W^-1 mu^T with W positive definite, and the distributions are non-integrable for every
nonzero radius or offset)."""

import json
import re
import tomllib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import EXAMPLES, run_inprocess

KEYS = ("regular", "rank_c", "status", "free_multipliers", "integrable", "first_class",
        "second_class", "parameter_case", "redundant")
EXAMPLES_SCALED = ("rolling_disk.toml", "differential_drive.toml", "ball_on_turntable.toml")


def verdict(path):
    rc, out, err = run_inprocess("classify", str(path), "--json")
    assert rc == 0, err
    env = json.loads(out)
    res = env["result"]
    return ({k: res[k] for k in KEYS}, [s["rank"] for s in res["stages"]], env["warnings"])


def scaled(example, factor, tmp_path):
    text = (EXAMPLES / example).read_text()
    params = tomllib.loads(text)["parameters"]
    table = ", ".join(f"{k} = {v * factor!r}" for k, v in params.items())
    text = re.sub(r"^parameters = \{.*\}$", f"parameters = {{{table}}}", text, flags=re.M)
    text = text.split("\n[initial]")[0]  # the initial state no longer satisfies the constraints
    path = tmp_path / f"{factor:g}_{example}"
    path.write_text(text)
    return path


@pytest.mark.parametrize("example", EXAMPLES_SCALED)
@pytest.mark.parametrize("factor", [1e-12, 1e12])
def test_scaling_every_parameter_keeps_the_verdict(example, factor, tmp_path):
    assert verdict(scaled(example, factor, tmp_path)) == verdict(EXAMPLES / example)


@settings(max_examples=6, deadline=None)
@given(exponent=st.floats(min_value=-12, max_value=12))
def test_rolling_disk_verdict_at_any_scale(exponent, tmp_path_factory):
    path = scaled("rolling_disk.toml", 10.0 ** exponent, tmp_path_factory.mktemp("units"))
    assert verdict(path) == verdict(EXAMPLES / "rolling_disk.toml")
