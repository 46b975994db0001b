"""A symmetry stated in a scene: the ``[symmetry]`` table (``DESIGN.md`` §2, "Relative
equilibria").

The generator xi of a one-parameter group acting on Q, by coordinate, as expressions in
the coordinates and the parameters (a coordinate left out has component 0)::

    [symmetry]              # the rotation about the vertical, turning the
    yaw = "1"               # heading and the mass centre together
    x = "-y"
    y = "x"

Its tangent lift Xi = xi^A d/dq^A + (d xi^A/d q^B) v^B d/dv^A must leave L, the
constraints and the forces invariant; that is decided where it is used
(:func:`nhham.lagrangian.relative_symmetry.check_symmetry`). ``nhham linearize`` then
linearises a ``[steady]`` motion along xi (a relative equilibrium) in co-moving
variables. The entries are parsed (never evaluated as Python) against a table of the
coordinates and parameters.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping

import sympy as sp

from nhham.errors import ParseError
from nhham.system.expressions import parse_expression, to_text

__all__ = ["Symmetry", "symmetry_structure", "parse_symmetry"]


@dataclass(frozen=True, eq=False)   # hashed by identity: a key of the checks' cache
class Symmetry:
    """The generator xi of a symmetry, by coordinate.

    Attributes
    ----------
    components : mapping of str to sympy.Expr
        Coordinate -> xi's component (only those the table gives, in the coordinates'
        order).

    Examples
    --------
    >>> import sympy as sp
    >>> from nhham.system.symmetry import Symmetry
    >>> rotation = Symmetry({"x": -sp.Symbol("y"), "y": sp.Symbol("x"), "theta": sp.S.One})
    >>> rotation.field(sp.symbols("x y theta phi"))
    [-y, x, 1, 0]
    >>> rotation.to_toml_table()
    {'x': '-y', 'y': 'x', 'theta': '1'}
    """

    components: Mapping[str, sp.Expr]

    def field(self, coordinates) -> list:
        """xi's n components in the order of ``coordinates`` (Symbols or names)."""
        return [self.components.get(getattr(q, "name", q), sp.S.Zero) for q in coordinates]

    def to_toml_table(self) -> dict:
        """``{coordinate: expression text}``, as a scene's ``[symmetry]`` table holds it."""
        return {q: to_text(e) for q, e in self.components.items()}

    def numeric(self, coordinates, parameters):
        """``evaluate(Q, P) -> (xi, D)`` in numpy (complex arrays welcome): the rows of Q
        (K, n) in ``coordinates``' order and of P (K, len(parameters)) or None (the
        ``parameters`` values); D[k, A, B] = d xi^A / d q^B.

        Parameters
        ----------
        coordinates : sequence of str
        parameters : mapping of str to float
            Every parameter of the model (its order is that of P's columns).
        """
        import numpy as np

        q = [sp.Symbol(c) for c in coordinates]
        p = [sp.Symbol(k) for k in parameters]
        xi = self.field(q)
        D = [[sp.diff(e, s) for s in q] for e in xi]
        f_xi = sp.lambdify([q, p], xi, modules="numpy")
        f_D = sp.lambdify([q, p], D, modules="numpy")
        values = np.array([np.nan if v is None else float(v) for v in parameters.values()],
                          dtype=float)
        n = len(q)

        def evaluate(Q, P=None):
            Q = np.atleast_2d(Q)
            K = Q.shape[0]
            rows = np.broadcast_to(values, (K, len(values))) if P is None else np.atleast_2d(P)
            rows = np.broadcast_to(rows, (K, len(values)))
            X = np.array(np.broadcast_arrays(*f_xi(list(Q.T), list(rows.T)),
                                             np.zeros(K)))[:n].T
            flat = [e for row in f_D(list(Q.T), list(rows.T)) for e in row]
            J = np.array(np.broadcast_arrays(*flat, np.zeros(K)))[:n * n].T.reshape(K, n, n)
            return X, J

        return evaluate


def symmetry_structure(value, coordinates, problems) -> Mapping | None:
    """Check a raw ``[symmetry]`` table: an expression string (or a number) for some of
    the coordinates. Problems are appended (each naming ``symmetry.<key>``); the raw
    entries are returned, or None without a table."""
    if value is None:
        return None
    if not isinstance(value, dict):
        problems.append("symmetry: expected a table of coordinate = \"expression\" (the "
                        "generator xi by coordinate)")
        return None
    kept = {}
    for key, item in value.items():
        if key not in coordinates:
            problems.append(f"symmetry.{key}: not a coordinate (the table gives the generator "
                            f"xi by coordinate: {', '.join(coordinates)})")
        elif isinstance(item, bool) or not isinstance(item, (str, int, float)):
            problems.append(f"symmetry.{key}: expected an expression string or a number")
        else:
            kept[key] = item
    if not kept and not any(p.startswith("symmetry") for p in problems):
        problems.append("symmetry: the table gives no component (the generator would be 0)")
    return MappingProxyType(kept)


def parse_symmetry(raw: Mapping | None, coordinates, parameters) -> tuple:
    """Parse a checked ``[symmetry]`` table against the coordinates and parameters.

    Returns
    -------
    (Symmetry or None, list of str)
        The generator and the problems found (each naming its key).
    """
    if raw is None:
        return None, []
    table = {q: sp.Symbol(q) for q in coordinates}
    table.update({p: sp.Symbol(p) for p in parameters})
    out, problems = {}, []
    for q in coordinates:
        if q not in raw:
            continue
        item = raw[q]
        try:
            out[q] = (parse_expression(item, table, where=f"symmetry.{q}")
                      if isinstance(item, str) else sp.nsimplify(item))
        except ParseError as exc:
            problems.append(str(exc))
    if problems:
        return None, problems
    return Symmetry(MappingProxyType(out)), []
