"""The catalogue of published problems (``catalog.toml``), read into frozen records.

Variants as data: a problem is a scene, a source and quantities; a quantity names the
measure (:data:`nhham.problems.measures.MEASURES`) that computes it. Adding a problem is
adding a table to ``catalog.toml`` (and its scene to ``scenes/``).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Any, Mapping

__all__ = ["Problem", "Quantity", "problems", "problem", "scene_path"]


@dataclass(frozen=True)
class Quantity:
    """One published quantity.

    Attributes
    ----------
    name : str
    measure : str
        The key of its measure in :data:`~nhham.problems.measures.MEASURES`.
    args : mapping
        The measure's arguments.
    published : float, str or list
        The source's value; a str is a closed form in the scene's names (parameters,
        ``NAME_0`` for initial values, t); a list of [re, im] pairs is a spectrum.
    precision : float
        The absolute error the printed digits allow (half a unit of the last digit), or
        for a closed form the tolerance nhham is held to.
    closed_form : bool
        The source gives a formula (or an exact value), not printed digits.
    where : str
        Where in the source (table, equation).
    """

    name: str
    measure: str
    args: Mapping
    published: Any
    precision: float
    closed_form: bool = False
    where: str = ""


@dataclass(frozen=True)
class Problem:
    """A published problem: its scene, its source and its quantities (``define``: names
    its quantities use, as expressions in the scene's names: the source's variables)."""

    name: str
    title: str
    scene: str
    authors: str
    source: str
    venue: str
    checked: str
    quantities: tuple = field(default_factory=tuple)
    define: Mapping = field(default_factory=dict)

    @property
    def citation(self) -> str:
        return f"{self.authors}, {self.source}, {self.venue}"


@cache
def problems() -> tuple:
    """Every problem of ``catalog.toml``, in its order."""
    data = tomllib.loads(resources.files("nhham.problems").joinpath("catalog.toml")
                         .read_text(encoding="utf-8"))
    out = []
    for entry in data["problem"]:
        quantities = tuple(Quantity(q["name"], q["measure"], q.get("args", {}), q["published"],
                                    float(q["precision"]), bool(q.get("closed_form", False)),
                                    q.get("where", ""))
                           for q in entry["quantity"])
        out.append(Problem(entry["name"], entry["title"], entry["scene"], entry["authors"],
                           entry["source"], entry["venue"], entry["checked"], quantities,
                           dict(entry.get("define", {}))))
    return tuple(out)


def problem(name: str) -> Problem:
    """The problem called ``name``; KeyError naming the known ones otherwise."""
    for p in problems():
        if p.name == name:
            return p
    raise KeyError(f"no problem {name!r}; known: {', '.join(p.name for p in problems())}")


def scene_path(problem: Problem):
    """The path of the problem's scene (package data, ``scenes/``)."""
    return resources.files("nhham.problems").joinpath("scenes", problem.scene)
