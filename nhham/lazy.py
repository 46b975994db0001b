"""Public names of a package, imported on first use (PEP 562).

A package lists ``{name: module}`` and gets the module-level ``__getattr__``
and ``__dir__`` that import the defining module the first time a name is
read. So ``import nhham`` stays cheap, and a command that only classifies
never imports the integrators (or scipy.integrate, which alone takes a
second to import).
"""

from __future__ import annotations

from importlib import import_module
from typing import Callable, Mapping

__all__ = ["lazy_exports"]


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
