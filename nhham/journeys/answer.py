"""What every journey returns, and what every journey takes in.

A journey is one thing a user does with a scene (classify it, derive its dynamics,
linearise its steady motion, ...). It takes a scene (or a ``System``, or a scene file's
path) and returns an :class:`Answer`: the JSON-ready result the command prints under
``--json`` (:meth:`Answer.to_dict`), its text (:meth:`Answer.text`), its warnings, and
the library objects it was computed from (``payload``). The command is parse -> journey
-> render; a study calls the same journey at its points.
"""

from __future__ import annotations

import copy
import dataclasses
import warnings as _warnings
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping

from nhham.errors import InputError
from nhham.render.text import one_line

__all__ = ["Answer", "as_scene", "quiet_steps", "capture_warnings"]


@dataclass(frozen=True)
class Answer:
    """One journey's answer for one scene.

    Attributes
    ----------
    journey : str
        Its name, the command's (``"classify"``, ``"linearize"``, ...).
    data : mapping
        The result as plain JSON data (the ``result`` of ``nhham JOURNEY --json``; its
        schema: :func:`nhham.output_schema`, ``$defs/<journey>``).
    render : callable () -> str
        The text report (formed when asked).
    latex : callable (parse) -> str, or None
        The LaTeX report, ``parse`` reading the result's expressions back
        (:func:`nhham.render.names.expression_parser`); None where there is none.
    warnings : tuple of str
        One line each.
    failure : str or None
        When the computation did not succeed (a run that stopped early): why, and what
        to do, in one line.
    payload : mapping
        The library objects the answer was made from (a verdict, a linearisation, a
        simulation result...), by name.
    system : System or None
        The system the answer is for (the scene's, at its values).

    Examples
    --------
    >>> from nhham import models, classify
    >>> answer = classify(models.rolling_disk())
    >>> answer.journey, answer.succeeded, answer.to_dict()["status"]
    ('classify', True, 'determined')
    >>> print(answer.text().splitlines()[0])
    vertical rolling disk: n = 4 coordinates, m = 2 velocity constraints
    """

    journey: str
    data: Mapping[str, Any]
    render: Callable[[], str]
    latex: Callable[[Callable], str] | None = None
    warnings: tuple = ()
    failure: str | None = None
    payload: Mapping[str, Any] = field(default_factory=dict)
    system: Any = None

    def to_dict(self) -> dict:
        """The result as a new plain dict (changing it changes nothing here)."""
        return copy.deepcopy(dict(self.data))

    def text(self) -> str:
        """The text report, as the command prints it."""
        return self.render()

    def latex_text(self) -> str:
        """The LaTeX report, as ``--latex`` prints it.

        Raises
        ------
        InputError
            The journey has no LaTeX form.
        """
        from nhham.render.names import expression_parser

        if self.latex is None:
            raise InputError(f"{self.journey}: --latex is not available (use --json or text)",
                             key="--latex")
        return self.latex(expression_parser(self.system))

    @property
    def succeeded(self) -> bool:
        """Whether the computation succeeded (no ``failure``)."""
        return self.failure is None

    def with_data(self, **entries) -> "Answer":
        """The same answer with entries of ``data`` added or replaced."""
        return dataclasses.replace(self, data={**self.data, **entries})

    def __str__(self) -> str:
        return self.text()


def as_scene(scene_or_system, *, initial=None, steady=None, **load_options):
    """A :class:`~nhham.system.scene.Scene` from a scene, a scene file's path, a ``System``
    or a ``sympy.physics.mechanics.System`` (wrapped in a scene; ``initial`` and
    ``steady`` give its tables).

    Parameters
    ----------
    scene_or_system : Scene, System, sympy.physics.mechanics.System, str or Path
    initial, steady : mapping, optional
        The ``[initial]`` and ``[steady]`` tables, keyed by nhham's names, dynamicsymbols
        ``q(t)``, ``q(t).diff(t)`` or a mechanics model's speeds ``u(t)``
        (:mod:`nhham.system.state_keys`); only the independent entries are needed, the
        others are solved (a steady motion's at any parameter values it is asked at; its
        inputs are given too). They replace the scene's.
    **load_options
        For :func:`nhham.load_scene` when a path is given (e.g. ``values=``; for a
        mechanics System, ``values`` are its parameters' values).

    Raises
    ------
    InputError
        Anything else, or tables that name something the system does not have.

    Examples
    --------
    >>> from nhham import System
    >>> scene = as_scene(System(["x", "y"], "(x_dot**2 + y_dot**2)/2", ["y_dot - 2*x_dot"]),
    ...                  steady={"x": 0, "y": 0, "x_dot": 1})
    >>> {k: float(v) for k, v in scene.steady.expressions.items()}
    {'x': 0.0, 'y': 0.0, 'x_dot': 1.0, 'y_dot': 2.0}
    """
    import dataclasses as _dc

    from nhham.system.description import System
    from nhham.system.scene import Scene, SimulateOptions, load_scene

    from nhham.system.state_keys import as_system

    scene_or_system, speeds = as_system(scene_or_system, load_options.get("values"))
    if isinstance(scene_or_system, Scene):
        scene = scene_or_system
    elif isinstance(scene_or_system, (str, Path)):
        scene = load_scene(scene_or_system, **load_options)
    elif isinstance(scene_or_system, System):
        scene = Scene(name=scene_or_system.name, description="", system=scene_or_system,
                      initial=None, simulate=SimulateOptions(), source="<System>")
    else:
        raise InputError(f"expected a Scene, a System or a scene file's path, got "
                         f"{type(scene_or_system).__name__}")
    if initial is not None:
        scene = _dc.replace(scene, **_initial_table(scene.system, initial, speeds))
    if steady is not None:
        scene = _dc.replace(scene, steady=_steady_table(scene.system, steady, speeds))
    return scene


def _initial_table(system, mapping, speeds) -> dict:
    """The Scene fields of an [initial] given in Python (solved as a scene's is)."""
    from types import MappingProxyType

    from nhham.system.initial_solve import InitialData
    from nhham.system.state_keys import completed_state, state_entries

    given = state_entries(system, mapping, speeds=speeds)
    state, solved = completed_state(system, given)
    return {"initial": MappingProxyType(state), "initial_solved": solved,
            "initial_given": InitialData(MappingProxyType(given), MappingProxyType({})),
            "initial_problem": None}


def _steady_table(system, mapping, speeds):
    """A [steady] given in Python: the entries given (expressions in the parameters), the
    others solved at the parameters' values, and again at others
    (:func:`~nhham.system.state_keys.steady_table`); the inputs' values passed through."""
    from nhham.system.state_keys import steady_table

    return steady_table(system, mapping, speeds=speeds)


def quiet_steps(steps=None):
    """``steps``, or a recorder that shows nothing (the library's default)."""
    from nhham.render.text import Steps

    return Steps(progress=False) if steps is None else steps


@contextmanager
def capture_warnings() -> Iterator[list]:
    """Collect Python warnings issued inside the block as one-line messages.

    Nothing is printed: the command reports them itself (in the envelope, or
    one ``nhham: warning:`` line each on stderr).
    """
    caught: list[str] = []
    with _warnings.catch_warnings(record=True) as records:
        _warnings.simplefilter("always")
        try:
            yield caught
        finally:
            caught.extend(one_line(r.message) for r in records)
