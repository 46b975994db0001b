"""Public names of a package, imported on first use (PEP 562).

A package lists its public names by defining module (:func:`by_module` turns
that into the ``{name: module}`` table) and gets the module-level ``__getattr__``
and ``__dir__`` that import the defining module the first time a name is
read. So ``import nhham`` stays cheap, and a command that only classifies
never imports the integrators (or scipy.integrate, which alone takes a
second to import).
"""

from __future__ import annotations

from importlib import import_module
from typing import Callable, Iterable, Mapping

__all__ = ["by_module", "lazy_exports"]


def by_module(groups: Mapping[str, Iterable[str]]) -> dict[str, str]:
    """The ``{name: module}`` table of names listed by defining module.

    Parameters
    ----------
    groups : mapping of str to iterable of str
        Module (relative to the package) -> the public names it defines, in the
        order ``__all__`` lists them.

    Examples
    --------
    >>> by_module({"system.scene": ("load_scene", "Scene"), "budget": ("time_budget",)})
    {'load_scene': 'system.scene', 'Scene': 'system.scene', 'time_budget': 'budget'}
    """
    return {name: module for module, names in groups.items() for name in names}


def lazy_exports(package: str, table: Mapping[str, str], namespace: dict
                 ) -> tuple[Callable[[str], object], Callable[[], list]]:
    """``(__getattr__, __dir__)`` for ``package`` exporting the names of ``table``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    table : mapping of str to str
        Public name -> module (relative to ``package``) that defines it. A
        module whose last component is the name and which defines no such
        attribute is itself the value (``"models": "system.models"``).
    namespace : dict
        The package's ``globals()``; a resolved name is stored there, so the
        next read does not come back here.
    """

    def __getattr__(name):
        if name not in table:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module = import_module(f".{table[name]}", package)
        if hasattr(module, name):
            value = getattr(module, name)
        elif table[name].rsplit(".", 1)[-1] == name:
            value = module
        else:
            raise AttributeError(f"{package}.{table[name]} does not define {name!r}")
        namespace[name] = value
        return value

    def __dir__():
        return sorted(set(namespace) | set(table))

    return __getattr__, __dir__
