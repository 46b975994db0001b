"""The one JSON contract of the ``nhham`` command.

Every subcommand run with ``--json`` prints exactly one object, the envelope::

    {
      "command": "classify",             # the subcommand
      "nhham_version": "0.1.0",
      "scene": {...},                    # where the input came from, and its names
      "result": {...},                   # the subcommand's own result
      "warnings": ["one line", ...],     # each warning one line, no Python text
      "error": null                      # or {kind, message, key} when it failed
    }

Keys are snake_case and each key has one JSON type in every command (numbers
as numbers, ``null`` for "not available"). Expressions are strings printed
by :func:`nhham.system.expressions.to_text`; read them back with
``nhham.parse_expression(text, envelope["scene"]["names"])`` (``I``, ``E``,
``S``, ``N`` are then the scene's parameters, not sympy's constants). The
JSON Schema is :func:`nhham.render.schema.output_schema` (the file
``nhham/render/schemas/output.schema.json``).

Exit status: :data:`EXIT_OK` (0) success, :data:`EXIT_INTERNAL` (1) an
internal failure, :data:`EXIT_INPUT` (2) bad input or usage,
:data:`EXIT_NOT_SUCCEEDED` (3) the command ran but its computation did not
succeed (a simulation that stopped early) or its ``--budget`` ran out,
:data:`EXIT_INTERRUPTED` (130) Ctrl-C. Whatever
the status, ``--json`` prints exactly one envelope; when the command failed its
``error`` is ``{kind, message, key}`` (:func:`error_info`, kinds in
:data:`ERROR_KINDS`), ``result`` is null unless the command ran to its end
(kind ``failed``: a result that says what did not succeed), and stderr has the
same message as one line.

Any subcommand (present or future) builds its output with :func:`envelope`
and :func:`scene_info`, and gathers warnings with :func:`capture_warnings`.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass, field
from typing import Any, Callable

from nhham.render.schema import jsonable
from nhham.journeys.answer import capture_warnings
from nhham.render.text import one_line
from nhham.settings import json_number

__all__ = [
    "EXIT_OK",
    "EXIT_INTERNAL",
    "EXIT_INPUT",
    "EXIT_NOT_SUCCEEDED",
    "EXIT_INTERRUPTED",
    "ERROR_KINDS",
    "CommandOutput",
    "envelope",
    "scene_info",
    "error_info",
    "FailureReport",
    "print_json",
    "one_line",
    "capture_warnings",
]

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_INPUT = 2
EXIT_NOT_SUCCEEDED = 3
#: Ctrl-C, at any point of a command (128 + SIGINT, as shells report it).
EXIT_INTERRUPTED = 130

#: ``error.kind`` of a failed command -> its exit status: ``usage`` (the command line)
#: and ``input`` (the scene, its data) exit 2; ``internal`` exits 1; ``budget``
#: (``--budget`` ran out), ``computation`` (a :class:`~nhham.errors.ComputationError`:
#: a computation could not be carried out, no result) and ``failed`` (the computation
#: ran but did not succeed; ``result`` says how) exit 3; ``interrupted`` (Ctrl-C)
#: exits 130.
ERROR_KINDS = {"usage": EXIT_INPUT, "input": EXIT_INPUT, "internal": EXIT_INTERNAL,
               "interrupted": EXIT_INTERRUPTED, "budget": EXIT_NOT_SUCCEEDED,
               "computation": EXIT_NOT_SUCCEEDED, "failed": EXIT_NOT_SUCCEEDED}


@dataclass
class CommandOutput:
    """What a subcommand hands to :func:`nhham.cli.main.main`.

    Attributes
    ----------
    result : dict
        The ``result`` of the JSON envelope.
    text : callable returning str, or str
        The human-readable output (built only when no ``--json`` was asked).
    scene : dict or None
        :func:`scene_info` of the input.
    warnings : list of str
        Warnings of the computation (one line each).
    failure : str or None
        When the computation did not succeed: one line saying why and what to
        do. The command then exits with the status of ``failure_kind``.
    failure_kind : str
        The ``error.kind`` of a failure (:data:`ERROR_KINDS`): ``failed`` (exit 3), or
        ``interrupted`` (a run stopped by Ctrl-C that kept its states: exit 130, the
        output printed all the same).
    """

    result: dict
    text: Callable[[], str] | str = ""
    scene: dict | None = None
    warnings: list = field(default_factory=list)
    failure: str | None = None
    failure_kind: str = "failed"

    def render_text(self) -> str:
        return self.text() if callable(self.text) else str(self.text)


def _dedupe(lines) -> list:
    out: list[str] = []
    for line in lines:
        line = one_line(line)
        if line and line not in out:
            out.append(line)
    return out


def envelope(command: str | None, result: dict | None, *, scene: dict | None = None,
             warnings=(), error: dict | None = None) -> dict:
    """The JSON object printed by ``nhham COMMAND --json``.

    Parameters
    ----------
    command : str or None
        The subcommand's name (None when the command line named none).
    result : dict or None
        Its result (JSON-ready; see :func:`jsonable`); None when it failed before
        having one.
    scene : dict, optional
        :func:`scene_info` of the scene it ran on.
    warnings : iterable of str
        Warnings; each becomes one line, duplicates are dropped.
    error : dict, optional
        :func:`error_info` of the failure; None (the default) on success.

    >>> env = envelope("classify", {"status": "determined"})
    >>> sorted(env)
    ['command', 'error', 'nhham_version', 'result', 'scene', 'warnings']
    >>> envelope("simulate", None, error=error_info("usage", "--atol: must be > 0",
    ...                                             "--atol"))["error"]
    {'kind': 'usage', 'message': '--atol: must be > 0', 'key': '--atol'}
    """
    from nhham.settings import __version__

    return {"command": command, "nhham_version": __version__, "scene": scene,
            "result": None if result is None else jsonable(result),
            "warnings": _dedupe(warnings), "error": error}


def error_info(kind: str, message, key: str | None = None) -> dict:
    """``error`` of the envelope: ``{kind, message, key}``.

    Parameters
    ----------
    kind : str
        One of :data:`ERROR_KINDS`.
    message : str
        What went wrong and what to do (made one line).
    key : str, optional
        The scene key path (``constraints[1]``) or option (``--atol``) at fault.
    """
    if kind not in ERROR_KINDS:
        raise ValueError(f"error kind {kind!r} is not one of {', '.join(ERROR_KINDS)}")
    return {"kind": kind, "message": one_line(message), "key": key}


def scene_info(scene) -> dict:
    """Where the input came from and every name an expression in the output may use.

    ``names`` lists coordinates, velocities, momenta, parameters and the
    multipliers ``lambda_i``: pass it to :func:`nhham.parse_expression`.
    """
    from nhham.render.names import output_names
    from nhham.system.naming import momentum_symbol

    system = scene.system
    values = {p: v for p, v in getattr(system, "parameter_values", {}).items()}
    params = [{"name": p.name, "value": json_number(values[p]) if p in values else None}
              for p in system.parameters]
    coords = [q.name for q in system.coordinates]
    vels = [v.name for v in system.velocities]
    momenta = [momentum_symbol(q).name for q in system.coordinates]
    given = getattr(scene, "values_set", {}) or {}
    return {"path": str(scene.source), "name": scene.name, "coordinates": coords,
            "velocities": vels, "momenta": momenta, "parameters": params,
            "names": output_names(system),
            "set": {k: json_number(v) for k, v in given.items()}}


def print_json(data) -> None:
    """Print one JSON document on stdout (non-finite numbers are refused: see jsonable)."""
    print(json.dumps(data, indent=2, allow_nan=False))


@dataclass(frozen=True)
class FailureReport:
    """Where a command's failure is reported: one line on stderr, and with ``--json``
    the envelope with its ``error`` on stdout.

    Attributes
    ----------
    command : str or None
        The subcommand, as far as the command line was understood.
    json : bool
        Whether ``--json`` was asked for.
    scene : callable returning a Scene or None
        The scene once loaded (the envelope's ``scene`` then names it).
    """

    command: str | None
    json: bool
    scene: Callable[[], Any] = lambda: None

    def fail(self, kind: str, message, key: str | None = None, *,
             prefix: str = "nhham: error: ", warnings=()) -> int:
        """Report a failure of ``kind`` that left no result; returns its exit status."""
        print(prefix + one_line(message), file=sys.stderr)
        if self.json:
            scene = self.scene()
            print_json(envelope(self.command, None, warnings=warnings,
                                scene=None if scene is None else scene_info(scene),
                                error=error_info(kind, message, key)))
        return ERROR_KINDS[kind]
