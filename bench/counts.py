"""How much work one command does: geometries, sides, samplers and points built.

Runs ``nhham <command> <scene> --json`` in this process with the constructors of
the exact half's objects wrapped in counters, and prints one row per command:

* ``geometries``: :class:`LagrangianGeometry` objects built;
* ``H sides``: :class:`HamiltonianSide` objects built;
* ``submanifolds``: :class:`Submanifold` objects (each samples float points on demand);
* ``samplers``: samplers of exact points (every class whose name ends in ``Sampler``
  or ``ComparisonPoints`` found in the modules below, and the exact-point sampler);
* ``exact points``: exact points drawn (rational, modular or over the parameter field);
* ``float points``: float points of a submanifold projected onto it.

The classes are looked up by name in the modules listed in ``WHERE``; a class that
is not there (renamed by a refactoring) is reported, not silently skipped.

Usage::

    python bench/counts.py examples/rolling_disk.toml examples/snakeboard.toml
    python bench/counts.py --commands classify,derive examples/rolling_disk.toml
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import importlib
import io
import sys
from collections import Counter
from pathlib import Path

# The tree this script is in, not an installed copy.
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

WHERE = (  # a module not in the tree (renamed since) is skipped
    "nhham.lagrangian.parametric",
    "nhham.lagrangian.geometry",
    "nhham.lagrangian.points",
    "nhham.lagrangian.submanifold",
    "nhham.lagrangian.exceptional",
    "nhham.hamiltonian.side",
    "nhham.hamiltonian.crosscheck",
    "nhham.hamiltonian.classification",
)
CONSTRUCTED = {
    "LagrangianGeometry": "geometries",
    "HamiltonianSide": "H sides",
    "Submanifold": "submanifolds",
}
SAMPLER_SUFFIXES = ("Sampler", "ComparisonPoints")
# (class, method) -> counter; the method returns one point a call, or a list of points.
DRAWS = {
    ("PointSampler", "point"): "exact points",
    ("ParameterFieldSampler", "point"): "exact points",
    ("_ParameterFieldSampler", "point"): "exact points",
    ("Submanifold", "_raw_points"): "float points",
}
COLUMNS = ("geometries", "H sides", "submanifolds", "samplers", "exact points", "float points")


def _classes():
    found = {}
    for name in WHERE:
        try:
            module = importlib.import_module(name)
        except ImportError:
            continue
        for attr, value in vars(module).items():
            if isinstance(value, type) and value.__module__ == name:
                found[attr] = value
    return found


def _wrap_init(cls, counts, key):
    original = cls.__init__

    @functools.wraps(original)
    def init(self, *args, **kwargs):
        if type(self) is cls or key == "samplers":
            counts[key] += 1
        original(self, *args, **kwargs)

    cls.__init__ = init
    return lambda: setattr(cls, "__init__", original)


def _wrap_draw(cls, method, counts, key):
    original = getattr(cls, method)

    @functools.wraps(original)
    def draw(self, *args, **kwargs):
        out = original(self, *args, **kwargs)
        counts[key] += len(out) if isinstance(out, list) else 1
        return out

    setattr(cls, method, draw)
    return lambda: setattr(cls, method, original)


def count(command: str, scene: str) -> tuple[Counter, list[str]]:
    """The counters of one command run in this process, and the classes not found."""
    import sympy as sp

    from nhham.cli.main import main

    sp.core.cache.clear_cache()
    classes = _classes()
    counts: Counter = Counter()
    undo, missing = [], []
    for name, key in CONSTRUCTED.items():
        if name in classes:
            undo.append(_wrap_init(classes[name], counts, key))
        else:
            missing.append(name)
    for name, cls in classes.items():
        if name.endswith(SAMPLER_SUFFIXES) and name not in CONSTRUCTED:
            undo.append(_wrap_init(cls, counts, "samplers"))
    for (name, method), key in DRAWS.items():
        if name in classes and hasattr(classes[name], method):
            undo.append(_wrap_draw(classes[name], method, counts, key))
    found = {name for name, _ in DRAWS if name in classes}
    if not {"ParameterFieldSampler", "_ParameterFieldSampler"} & found:
        missing.append("ParameterFieldSampler.point")
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            main([command, scene, "--json"])
    finally:
        for restore in undo:
            restore()
    return counts, missing


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="+")
    parser.add_argument("--commands", default="classify,derive,compare")
    args = parser.parse_args(argv)
    print(f"{'scene':32} {'command':9} " + " ".join(f"{c:>12}" for c in COLUMNS))
    for scene in args.scenes:
        for command in args.commands.split(","):
            counts, missing = count(command, scene)
            print(f"{scene.rsplit('/', 1)[-1]:32} {command:9} "
                  + " ".join(f"{counts[c]:>12}" for c in COLUMNS))
            if missing:
                print(f"    not found: {', '.join(missing)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
