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
