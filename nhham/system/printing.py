"""Expressions as text in a scene's own names: :func:`to_text`, the inverse of
:func:`nhham.system.expressions.parse_expression` (re-exported there), and :func:`short`
for messages.

Examples
--------
>>> import sympy as sp
>>> from nhham.system.printing import to_text
>>> x = sp.Symbol("x")
>>> to_text(sp.E ** x + 0.1 * x)
'0.1*x + exp(x)'
"""

from __future__ import annotations

import math

import sympy as sp
from sympy.printing.str import StrPrinter

__all__ = ["to_text", "short"]

#: Printed subexpressions a printer keeps (then it starts afresh): derived entries share
#: large subtrees (the bicycle's forcing repeats its frames' rotations), printed once each.
_MEMO_SIZE = 1 << 16


class _ScenePrinter(StrPrinter):
    """sympy's str printer, adjusted so the output parses back exactly.

    Floats print with ``repr`` of the double (17 significant digits when
    needed), and constants that sympy creates on its own print in terms of
    the allowed functions: ``exp(1)`` instead of ``E``, ``sqrt(-1)`` instead
    of ``I`` -- in a scene, ``E`` and ``I`` are ordinary names.
    """

    def _print(self, expr, **kwargs):
        # Memoised by expression: the text of a subtree depends on the settings only
        # (a call with options, as _print_Add(order=...), is printed afresh).
        if kwargs:
            return super()._print(expr, **kwargs)
        memo = self.__dict__.setdefault("_memo", {})
        text = memo.get(expr)
        if text is None:
            if len(memo) >= _MEMO_SIZE:
                memo.clear()
            text = memo[expr] = super()._print(expr)
        return text

    def _print_Float(self, expr):
        if expr._prec == 53:  # a double: repr is the shortest exact form
            value = float(expr)
            if math.isfinite(value):
                return repr(value)
        return super()._print_Float(expr)

    def _print_Exp1(self, expr):
        return "exp(1)"

    def _print_ImaginaryUnit(self, expr):
        return "sqrt(-1)"


_PRINTER = _ScenePrinter({"full_prec": True})
# Sorting the terms of a sum costs three times the printing itself: entries longer than
# this keep sympy's stored (deterministic) order; the shorter ones, read by eye, are sorted.
_UNSORTED = _ScenePrinter({"full_prec": True, "order": "none"})
SORTED_TEXT_LIMIT = 2000


def to_text(expr) -> str:
    """Print an expression so that :func:`parse_expression` reads it back.

    Parameters
    ----------
    expr : sympy.Expr
        An expression in the scene's symbols and the functions of
        :data:`FUNCTIONS`.

    Returns
    -------
    str
        Text in the scene's own names (``Abs``, ``atan2``, ``sqrt``...);
        ``parse_expression(to_text(e), table, ...) == e`` and, for names that
        are not Python keywords or sympy constants, ``sympy.sympify`` reads it
        back too. Terms are in sympy's printing order up to
        :data:`SORTED_TEXT_LIMIT` characters, in its stored order beyond.
    """
    expr = sp.sympify(expr)
    text = _UNSORTED.doprint(expr)
    return _PRINTER.doprint(expr) if len(text) <= SORTED_TEXT_LIMIT else text


def short(expr, limit: int = 80) -> str:
    """``str(expr)`` cut to ``limit`` characters (with ``...``), for messages."""
    text = str(expr)
    return text if len(text) <= limit else text[:limit - 3] + "..."
