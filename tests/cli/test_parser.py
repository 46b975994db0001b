"""The command line (nhham.cli.parser): the default budget, options a command does not
take named with the commands that do, usage errors as one line naming the option."""

from pathlib import Path

import pytest

from nhham.cli.parser import build_parser, unknown_options
from nhham.errors import UsageError

DISK = Path(__file__).resolve().parents[2] / "examples" / "rolling_disk.toml"


def test_no_bound_on_request():
    """--budget none lifts the default bound of the symbolic commands."""
    args = build_parser().parse_args(["classify", str(DISK), "--budget", "none"])
    assert args.budget is None
    assert build_parser().parse_args(["classify", str(DISK)]).budget == 600
    assert build_parser().parse_args(["simulate", str(DISK)]).budget is None


def test_options_of_other_commands_are_named_with_them():
    """--precision belongs to the symbolic commands, --quick to bench alone; a stray word
    is an unexpected argument, unless it is the value of an unknown option before it."""
    parser = build_parser()
    assert unknown_options(parser, "simulate", ["--precision", "30"]) == (
        "simulate has no option --precision (it is an option of classify, derive, compare)")
    assert unknown_options(parser, "classify", ["--quick", "extra"]) == (
        "classify has no option --quick (it is an option of bench)")
    assert unknown_options(parser, "classify", ["stray", "--frobnicate=1"]) == (
        "unexpected argument 'stray'; classify has no option --frobnicate")


@pytest.mark.parametrize("argv, key", [
    (["simulate", "s.toml", "--method", "euler"], "--method"),
    (["derive", "s.toml", "--side", "both"], "--side"),
    (["classify"], "scene"),
    (["bogus", "s.toml"], "command"),
    (["compare", "s.toml", "--samples", "six"], "--samples"),
])
def test_usage_errors_are_one_line_naming_the_option(argv, key):
    with pytest.raises(UsageError) as info:
        build_parser().parse_args(argv)
    message = str(info.value)
    assert info.value.key == key
    assert "\n" not in message and message.endswith("--help`)")
