"""The command line's option values, checked before any work.

Every option has a range. :func:`check_options` runs once, right after the command
line is read and before the scene is loaded: it collects every value out of its
range and raises one :class:`~nhham.errors.UsageError` naming each offending option
(the command exits 2; with ``--json`` the envelope's ``error.key`` is the first
option). Options that only make sense together (``--depth`` without
``--parametric``) and files that could not be written after the work
(``--output``, ``--plot``) are refused here too. The ranges of the simulation
options are those of a scene's ``[simulate]`` table
(:func:`nhham.system.scene.simulate_option_problem`).
"""

from __future__ import annotations

import argparse
import math
import os
import re
from pathlib import Path

from nhham.errors import InputError, UsageError
from nhham.settings import MAX_DIGITS, MIN_DIGITS, option_problem

__all__ = ["DEFAULT_BUDGET", "MAX_BUDGET", "budget_value", "check_options", "argparse_key",
           "set_values"]

#: Default ``--budget`` (seconds) of the symbolic commands (classify, derive, compare,
#: linearize); simulate and bench have none (they report their progress).
DEFAULT_BUDGET = 600.0

#: Largest ``--budget`` (seconds, about 11.6 days): beyond it ``--budget none``.
MAX_BUDGET = 1e6

# Options of `simulate` and `bench` with the range of a [simulate] table entry.
_SIMULATE_RANGES = ("t_end", "rtol", "atol", "step", "max_step")


def budget_value(text: str) -> float | None:
    """``--budget`` as argparse reads it: seconds, or ``none`` for no bound."""
    if text.strip().lower() == "none":
        return None
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a number of seconds or 'none', got {text!r}") from None


def argparse_key(message: str) -> str | None:
    """The option (or argument) an argparse error message is about, or None.

    >>> argparse_key("argument --method: invalid choice: 'euler'")
    '--method'
    >>> argparse_key("the following arguments are required: scene")
    'scene'
    """
    message = str(message)
    if message.startswith("argument "):
        name = message[len("argument "):].split(":")[0].split("/")[0]
    elif "arguments are required: " in message:
        name = message.split("arguments are required: ")[1].split(",")[0].strip()
    else:
        return None
    return name.lower() if name.isupper() else name  # the metavar COMMAND is the command


def check_options(args: argparse.Namespace) -> None:
    """Check every option of ``args`` against its range.

    Raises
    ------
    UsageError
        Naming every offending option and its value (``key``: the first one).
    """
    problems: list[str] = []
    _check_budget(args, problems)
    _check_digits(args, problems)
    _check_combinations(args, problems)
    for key, least in (("save_every", 1), ("max_points", 2)):
        value = getattr(args, key, None)
        if value is not None and value < least:
            problems.append(f"{_option(key)}: expected at least {least}, got {value}")
    samples = getattr(args, "samples", None)
    why = None if samples is None else option_problem("samples", samples)
    if why:
        problems.append(f"--samples: {why}")
    t_end = getattr(args, "t_end", None)
    for key in _SIMULATE_RANGES:
        value = getattr(args, key, None)
        if value is not None:
            from nhham.system.scene import simulate_option_problem

            problem = simulate_option_problem(key, value, t_end)
            if problem:
                problems.append(f"{_option(key)}: {problem}")
    for key in ("output", "plot"):
        if getattr(args, key, None) is not None:
            problem = _output_problem(getattr(args, key), key == "plot")
            if problem:
                problems.append(f"--{key}: {problem}")
    try:
        args.parameter_values = set_values(getattr(args, "set_values", None) or [])
    except InputError as exc:
        problems.append(str(exc))
    sweep = getattr(args, "sweep", None)
    if sweep is not None:
        from nhham.cli.linearize_command import parse_sweep

        try:
            parse_sweep(sweep)
        except InputError as exc:  # its message names --sweep
            problems.append(str(exc))
    if problems:  # each starts with its option
        option = re.match(r"--[a-z-]+", problems[0])
        raise UsageError("; ".join(problems), key=option.group() if option else None)


def set_values(items) -> dict:
    """``--set NAME=VALUE`` (repeatable) as ``{name: value}``, each value checked as a
    scene's number is (:func:`nhham.system.scene.scene_number`: ``1e-400`` is refused);
    whether NAME is a parameter is checked when the scene loads.

    Raises
    ------
    InputError
        Naming ``--set`` and the item at fault.
    """
    from nhham.system.scene_numbers import scene_number

    out: dict = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name or not value.strip():
            raise InputError(f"--set: expected NAME=VALUE (e.g. --set m=2.5), got {item!r}",
                             key="--set")
        if name in out:
            raise InputError(f"--set: {name!r} given twice", key="--set")
        try:
            out[name] = scene_number(value, f"--set {name}")
        except InputError as exc:
            raise InputError(str(exc), key="--set") from None
    return out


def _option(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def _check_budget(args, problems) -> None:
    budget = getattr(args, "budget", None)
    if budget is None:
        return
    if not math.isfinite(budget) or budget <= 0:
        problems.append(f"--budget: expected a positive number of seconds (or 'none' for no "
                        f"bound), got {budget!r}")
    elif budget > MAX_BUDGET:
        problems.append(f"--budget: at most {MAX_BUDGET:.0e} seconds; for no bound give "
                        f"--budget none, got {budget!r}")


def _check_digits(args, problems) -> None:
    for key in ("precision", "reference_digits"):
        digits = getattr(args, key, None)
        if digits is not None and not MIN_DIGITS <= digits <= MAX_DIGITS:
            problems.append(f"{_option(key)}: expected {MIN_DIGITS} to {MAX_DIGITS} digits "
                            f"(more than float64's 16), got {digits}")


def _check_combinations(args, problems) -> None:
    """Options that would be ignored: refused rather than dropped without a word."""
    if getattr(args, "json", False) and getattr(args, "latex", False):
        problems.append("--latex: not with --json (the envelope has the expressions as text)")
    if not getattr(args, "parametric", True):
        for key in ("positive", "depth", "symbolic"):
            if getattr(args, key, None) is not None:
                problems.append(f"{_option(key)}: only with --parametric")
    if getattr(args, "sweep", "") is None and getattr(args, "plot", None) is not None:
        problems.append("--plot draws the root locus of a sweep: give --sweep too")
    depth = getattr(args, "depth", None)
    if depth is not None and depth < 0:
        problems.append(f"--depth: expected a non-negative integer, got {depth}")


def _output_problem(path_text: str, figure: bool) -> str | None:
    """Why a file could not be written at ``path_text`` (checked before the work), or None."""
    path = Path(path_text)
    if not path_text.strip():
        return "expected a file name, got an empty one"
    if path.is_dir():
        return f"{path_text!r} is a directory, not a file name"
    folder = path.parent
    if not folder.is_dir():
        return f"the directory {str(folder)!r} does not exist"
    if not os.access(folder, os.W_OK | os.X_OK) or (path.exists() and not os.access(path, os.W_OK)):
        return f"cannot write {path_text!r} (permission denied)"
    if figure:
        try:
            from matplotlib.backend_bases import FigureCanvasBase
        except ImportError:
            return ("plotting needs matplotlib, an optional extra: pip install 'nhham[plot]' "
                    "(or pip install matplotlib)")
        formats = FigureCanvasBase.get_supported_filetypes()
        suffix = path.suffix.lower().lstrip(".")
        if suffix not in formats:
            return (f"unknown figure format {path.suffix or '(no suffix)'!r}; use one of "
                    + ", ".join(f".{f}" for f in sorted(formats)))
    return None
