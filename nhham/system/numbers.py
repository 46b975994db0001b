"""Which numbers are data nhham computes with: real ones, within double precision.

A constant that is not a real number (``sqrt(-1)``, ``log(-1)`` = ``I*pi``,
``asin(2)``, the principal root ``(-1)**(1/3)``) would lose its imaginary part in
the numeric layer, and a float beyond double precision's range (``1e-400``) would
become 0 or infinite there: both are refused where the input comes in (the
expression parser, :class:`nhham.System`), naming the number and its value.
"""

from __future__ import annotations

import math

import sympy as sp

__all__ = ["number_problems", "complex_string", "value_problem"]

#: What a part of an expression may not become: 1/0, 0/0 (sympy's zoo, nan), infinity.
_NOT_FINITE = (sp.zoo, sp.nan, sp.oo, -sp.oo)


def number_problems(expr) -> list[str]:
    """Why the numbers in ``expr`` are not real data nhham can compute with.

    Every constant subexpression must be a real number (``sqrt(-1)``, ``log(-1)`` =
    ``I*pi``, ``asin(2)`` are not) and every float must lie within double
    precision's range (sympy's ``Float('1e-400')`` would become 0).

    Parameters
    ----------
    expr : sympy.Expr

    Returns
    -------
    list of str
        One line per offending number (empty when every number is fine).

    >>> number_problems(sp.asin(2) * sp.Symbol("x"))
    ['asin(2) is not a real number (its value is 1.5708-1.31696i); nhham takes real data only']
    """
    problems = []
    root = sp.sympify(expr)
    constant = _constant_nodes(root)
    stack = [root]
    while stack:
        node = stack.pop()
        if not isinstance(node, sp.Expr) or not constant[node]:
            stack.extend(node.args)
            continue
        for number in node.atoms(sp.Float):
            double = float(number)
            if not math.isfinite(double) or (double == 0.0 and not number.is_zero):
                problems.append(f"the number {sp.sstr(number)} is outside the range of double "
                                f"precision (about 1e-308 to 1e308)")
        complex_value = complex_string(node)
        if complex_value:
            problems.append(f"{sp.sstr(node)} is not a real number (its value is "
                            f"{complex_value}); nhham takes real data only")
    return problems


def _constant_nodes(root) -> dict:
    """Node -> whether it is free of symbols, for every node of ``root``'s tree, in one
    post-order walk (sympy recomputes ``free_symbols`` at every call: asked at every
    node, quadratic in the depth; 0.15 s on the bicycle's scene)."""
    constant: dict = {}
    stack = [(root, False)]
    while stack:
        node, ready = stack.pop()
        if node in constant:
            continue
        if ready or not node.args:
            constant[node] = (not isinstance(node, sp.Symbol)
                              and all(constant[a] for a in node.args))
            continue
        stack.append((node, True))
        stack.extend((a, False) for a in node.args if a not in constant)
    return constant


def complex_string(number) -> str | None:
    """The value of the constant ``number`` as ``a+bi`` when it is not real, else None.

    >>> complex_string(sp.asin(2)), complex_string(sp.acos(sp.Rational(1, 3)))
    ('1.5708-1.31696i', None)
    """
    real = number.is_extended_real
    if real:
        return None
    try:
        re, im = (float(part) for part in number.evalf(30).as_real_imag())
    except (TypeError, ValueError, OverflowError):
        return None  # not a number that evaluates: the numeric checks met later say so
    if not (math.isfinite(re) and math.isfinite(im)):
        return None  # not finite: refused as such
    if real is None and abs(im) <= 1e-25 * max(1.0, abs(re)):
        return None
    return f"{re:.6g}{im:+.6g}i"


def value_problem(expr, values) -> str | None:
    """Why ``expr`` is no real, finite datum once the parameters take their ``values``, or
    None: the smallest part that becomes infinite or undefined (``1/k``, ``atan2(k, k)``
    at k = 0) or a constant that is not real (``sqrt(k)`` at k = -1), with the values it
    uses. The parser and :func:`number_problems` see the written numbers only; the
    numeric layer would meet NaN, or drop an imaginary part, at every point.

    Parameters
    ----------
    expr : sympy.Expr
    values : mapping of sympy.Symbol to float
        The parameters' values (those without one stay symbols).

    Returns
    -------
    str or None

    >>> k, x = sp.symbols("k x")
    >>> value_problem(x / sp.atan2(k, 2) + 1, {k: 0.0})
    '1/atan2(k, 2) is not finite at k = 0 (it is zoo)'
    >>> value_problem(x * sp.sqrt(k), {k: -1.0})
    'sqrt(k) is not a real number at k = -1 (its value is 0+1i)'
    >>> value_problem(x / k, {k: 2.0}) is None
    True
    """
    root = sp.sympify(expr)
    used = root.free_symbols & set(values)
    if not used:
        return None
    exact = {p: sp.Rational(str(values[p])) for p in used}
    # Only a function or a power other than a polynomial one can turn finite values into
    # an infinite, undefined or complex one: those parts alone are evaluated (the whole
    # of a large L at its values costs a quarter of a second), lowest first.
    seen: set = set()
    for node in sp.postorder_traversal(root):
        if node in seen or not _partial(node) or not node.free_symbols & used:
            continue
        seen.add(node)
        value = node.xreplace(exact)
        if _bad_value(value):
            at = ", ".join(f"{p.name} = {values[p]:g}" for p in
                           sorted(node.free_symbols & used, key=lambda s: s.name))
            complex_value = complex_string(value) if not value.free_symbols else None
            if complex_value:
                return (f"{sp.sstr(node)} is not a real number at {at} (its value is "
                        f"{complex_value})")
            return f"{sp.sstr(node)} is not finite at {at} (it is {sp.sstr(value)})"
    return None


def _partial(node) -> bool:
    """A part that may be undefined where its arguments are finite: a function, or a
    power other than a nonnegative integer one."""
    if isinstance(node, sp.Pow):
        return not (node.exp.is_Integer and node.exp >= 0)
    return isinstance(node, sp.Function)


def _bad_value(value) -> bool:
    """Whether a part's value is infinite, undefined, or a constant that is not real."""
    if value.has(*_NOT_FINITE):
        return True
    return not value.free_symbols and complex_string(value) is not None
