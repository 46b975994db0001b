"""d expr/d x for the expressions of mechanical systems, faster than sympy's ``diff`` on
them (re-exported by :mod:`nhham.system.expressions`, where every caller finds it).

Examples
--------
>>> import sympy as sp
>>> from nhham.system.derivative import derivative
>>> x, y = sp.symbols("x y")
>>> derivative(x**2 * sp.sin(y) + y, x)
2*x*sin(y)
"""

from __future__ import annotations

import functools

import sympy as sp

__all__ = ["derivative", "symbols_in"]


@functools.lru_cache(maxsize=1 << 17)
def symbols_in(expr: sp.Basic) -> frozenset:
    """``expr.free_symbols``, memoised and built from the arguments' own (sympy walks
    the whole tree again at every node: a derivative asks at each level, the quadratic
    cost of a long row). Nodes with bound variables (Derivative, Integral, Lambda) ask
    sympy."""
    if expr.is_Atom:
        return frozenset(expr.free_symbols)
    if expr.is_Add or expr.is_Mul or expr.is_Pow or isinstance(expr, sp.Function):
        return frozenset().union(*(symbols_in(a) for a in expr.args))
    return frozenset(expr.free_symbols)


@functools.lru_cache(maxsize=1 << 17)
def derivative(expr: sp.Expr, x: sp.Symbol) -> sp.Expr:
    """d expr / d x by the sum, product, power and chain rules (sin, cos).

    The same derivative as ``expr.diff(x)`` (its fallback for any other node),
    without what makes sympy's ``diff`` slow on the entries of mechanical systems: a
    ``Derivative`` object per factor, also for factors free of x, and assumption
    queries on every result; only the factors that contain x are differentiated.
    Memoised (expressions are immutable): the analysis, the check at the parameter
    values, the classes and the cross-check differentiate the same rows again (the
    64-link snake's 64 x 66 rows and their subexpressions outgrew a cache of 16,384).
    """
    if x not in symbols_in(expr):
        return sp.S.Zero
    if expr.is_Symbol:
        return sp.S.One
    if expr.is_Add:
        return sp.Add(*[derivative(a, x) for a in expr.args if x in symbols_in(a)])
    if expr.is_Mul:
        args = expr.args
        return sp.Add(*[sp.Mul(*args[:i], derivative(a, x), *args[i + 1:])
                        for i, a in enumerate(args) if x in symbols_in(a)])
    if expr.is_Pow and x not in symbols_in(expr.exp):
        base, k = expr.args
        return k * base ** (k - 1) * derivative(base, x)
    if isinstance(expr, sp.sin):
        return _trig(sp.cos, expr.args[0]) * derivative(expr.args[0], x)
    if isinstance(expr, sp.cos):
        return -_trig(sp.sin, expr.args[0]) * derivative(expr.args[0], x)
    return expr.diff(x)


@functools.lru_cache(maxsize=1 << 16)
def _trig(f, u: sp.Expr) -> sp.Expr:
    """f(u), built once: sympy's own cache (1,000 entries) is outgrown by a 64-link
    snake's sin(theta_i - theta_j), whose evaluation is most of a derivative's cost."""
    return f(u)
