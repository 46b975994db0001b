"""From sympy expressions to numbers: the one route of the exact layers.

:func:`numeric_function` compiles expressions once into a Python function of numbers,
with numpy (float64) or mpmath (arbitrary precision) as the numeric module. The
submanifold decisions, the Legendre map's numeric helpers and the sampled checks all
go through it; the generated kernels of :mod:`nhham.numerics.codegen` are the other,
compiled, route (C and numpy code for integration).
"""

from __future__ import annotations

from typing import Callable, Sequence

import sympy as sp

__all__ = ["numeric_function", "numeric_module"]


def numeric_module(precision: int | None) -> str:
    """``"numpy"`` for float64 (precision None), ``"mpmath"`` otherwise."""
    return "numpy" if precision is None else "mpmath"


def numeric_function(args: Sequence, exprs, precision: int | None = None,
                     cse: bool = False) -> Callable:
    """``f(*values)`` evaluating ``exprs`` (an expression, a list or a Matrix) at ``args``.

    Parameters
    ----------
    args : sequence of sympy.Symbol
        The arguments, in order.
    exprs : sympy.Expr, list or sympy.Matrix
        What to evaluate; the result has the same nesting (numpy arrays for matrices).
    precision : int or None
        None: numpy, float64; an integer: mpmath (the caller sets ``mpmath.mp.dps``).
    cse : bool
        Common subexpressions extracted once (worth it for long lists).
    """
    from sympy.printing.numpy import NumPyPrinter
    from sympy.printing.pycode import MpmathPrinter

    # The terms of a sum are printed as they are stored: sorting them (sympy's default)
    # is most of the cost of printing the bicycle's matrices.
    printer = (NumPyPrinter if precision is None else MpmathPrinter)(
        {"fully_qualified_modules": False, "inline": True, "allow_unknown_functions": True,
         "user_functions": {}, "order": "none"})
    return sp.lambdify(list(args), exprs, modules=numeric_module(precision), cse=cse,
                       printer=printer)
