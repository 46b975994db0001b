"""Where the example generators (``make_*.py``) put the scene they write, and how it ends."""

import sys
from pathlib import Path

#: The ``[simulate]`` table of every generated scene.
SIMULATE = {"t_end": 10.0, "method": "DOP853", "rtol": 1e-10}


def write_scene(text: str, target: str) -> None:
    """Write a generated scene to the file ``target``, or to stdout when it is ``-``."""
    if target == "-":
        sys.stdout.write(text)
    else:
        Path(target).write_text(text, encoding="utf-8")


def write_example(argv, name: str, header: str, system, **tables) -> None:
    """Write ``header`` and the scene of ``system`` where the generator's command line says.

    Parameters
    ----------
    argv : list of str
        The generator's ``sys.argv``: ``argv[1]``, when given, is the target (``-`` for
        stdout); else the scene goes to ``name`` beside this file, in ``examples/``.
    name : str
        The scene's file name in ``examples/``.
    header : str
        The comment lines the scene starts with.
    system : nhham.System
    **tables
        The other keywords of :func:`nhham.dump_scene` (``initial``, ``steady``,
        ``description``); ``simulate`` is :data:`SIMULATE`.
    """
    # Imported here: make_snake.py writes its scene without dump_scene when it is missing.
    from nhham.system.scene_dump import dump_scene

    target = argv[1] if len(argv) > 1 else str(Path(__file__).resolve().parent / name)
    write_scene(header + dump_scene(system, simulate=SIMULATE, **tables), target)
