"""The option ranges of nhham.cli.options at their boundaries, every problem at once."""

import doctest
import importlib

import pytest

from nhham.cli import options
from nhham.errors import UsageError
from nhham.system.scene import MIN_RTOL

cli_main = importlib.import_module("nhham.cli.main")


def parsed(*argv):
    return cli_main.build_parser().parse_args([str(a) for a in argv])


@pytest.mark.parametrize("argv", [
    ("simulate", "s.toml", "--rtol", repr(MIN_RTOL)), ("simulate", "s.toml", "--rtol", "0.5"),
    ("simulate", "s.toml", "--budget", "1e6"), ("simulate", "s.toml", "--budget", "none"),
    ("classify", "s.toml", "--precision", "16"), ("derive", "s.toml", "--precision", "1000"),
    ("compare", "s.toml", "--samples", "1"), ("compare", "s.toml", "--samples", "1000"),
    ("simulate", "s.toml", "--method", "rattle", "--step", "10", "--t-end", "10"),
    ("simulate", "s.toml", "--method", "rattle", "--step", "1e-7", "--t-end", "10"),
    ("classify", "s.toml", "--parametric", "--depth", "0", "--positive", "m,R"),
])
def test_values_at_the_edge_of_their_range_pass(argv):
    options.check_options(parsed(*argv))


@pytest.mark.parametrize("argv, key", [
    (("simulate", "s.toml", "--rtol", repr(MIN_RTOL * 0.99)), "--rtol"),
    (("simulate", "s.toml", "--rtol", "1"), "--rtol"),
    (("simulate", "s.toml", "--budget", "1000001"), "--budget"),
    (("classify", "s.toml", "--precision", "15"), "--precision"),
    (("derive", "s.toml", "--precision", "1001"), "--precision"),
    (("compare", "s.toml", "--samples", "1001"), "--samples"),
    (("simulate", "s.toml", "--method", "rattle", "--step", "10.5", "--t-end", "10"), "--step"),
    (("simulate", "s.toml", "--method", "rattle", "--step", "1e-8", "--t-end", "10"), "--step"),
    (("classify", "s.toml", "--parametric", "--depth", "-1"), "--depth"),
])
def test_values_beyond_their_range_are_refused(argv, key):
    with pytest.raises(UsageError) as info:
        options.check_options(parsed(*argv))
    assert info.value.key == key and str(info.value).startswith(key)


def test_every_problem_at_once_the_first_is_the_key(tmp_path):
    with pytest.raises(UsageError) as info:
        options.check_options(parsed("simulate", "s.toml", "--atol", "-1", "--t-end", "0",
                                     "--output", str(tmp_path)))
    message = str(info.value)
    assert info.value.key == "--t-end"  # checked in the order of the ranges' table
    for option in ("--atol", "--t-end", "--output"):
        assert f"{option}: " in message
    assert "is a directory" in message


def test_budget_value_reads_seconds_or_none():
    assert options.budget_value("2.5") == 2.5 and options.budget_value("None") is None
    with pytest.raises(Exception, match="seconds or 'none'"):
        options.budget_value("soon")


def test_docstring_examples():
    assert doctest.testmod(options).failed == 0


def test_t_eval_chooses_the_output_times(tmp_path, capsys):
    """--t-eval 0:20:5 stores the states at t = 0, 5, 10, 15, 20 (the sleigh's [simulate]
    t_end), the energy conserved there; times outside [0, t_end], decreasing, or
    for a fixed-step method are refused naming --t-eval."""
    import numpy as np

    from nhham.cli.main import main, output_times

    out = tmp_path / "run.csv"
    assert main(["simulate", "examples/chaplygin_sleigh.toml", "--t-eval", "0:20:5",
                 "--output", str(out)]) == 0
    data = np.genfromtxt(out, delimiter=",", names=True)
    assert np.allclose(data["t"], [0, 5, 10, 15, 20], atol=0)
    # the sleigh (m = 1, I = 0.25, a = 0.5): the energy is conserved
    assert np.allclose(data["energy"], data["energy"][0], rtol=1e-9)
    for bad, why in (("0:30:5", "within"), ("3,1", "increase"), ("0:1:0", "at least 1"),
                     ("x", "expected")):
        with pytest.raises(UsageError, match=f"--t-eval: .*{why}"):
            output_times(bad, 20.0)
    capsys.readouterr()
    assert main(["simulate", "examples/chaplygin_sleigh.toml", "--method", "rk4", "--step",
                 "0.1", "--t-eval", "0:2:3"]) == 2
    assert "--t-eval" in capsys.readouterr().err
