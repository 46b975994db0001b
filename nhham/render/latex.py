"""LaTeX in the paper's notation: one printer for every command and report.

Generated names are printed as the paper writes them: a velocity ``x_dot``
as :math:`\\dot{x}`, an acceleration ``x_ddot`` as :math:`\\ddot{x}`, a
momentum ``p_theta`` as :math:`p_{\\theta}`, a multiplier ``lambda_1`` as
:math:`\\lambda_{1}`; every other name as sympy prints a symbol of that name
(``theta`` is :math:`\\theta`, ``I2`` is :math:`I_{2}`).

>>> import sympy as sp
>>> latex(sp.Symbol("theta_dot") * sp.Symbol("p_x") + sp.Symbol("lambda_1"))
'\\\\lambda_{1} + p_{x} \\\\dot{\\\\theta}'
"""

from __future__ import annotations

import re

import sympy as sp

__all__ = ["latex", "name_latex", "matrix_latex", "aligned", "text", "free_letter"]

_MULTIPLIER = re.compile(r"^lambda_(\d+)$")


def name_latex(name: str) -> str:
    """The LaTeX of one generated or user name (see the module docstring).

    >>> name_latex("x_dot"), name_latex("q1_ddot"), name_latex("p_phi")
    ('\\\\dot{x}', '\\\\ddot{q}_{1}', 'p_{\\\\phi}')
    """
    if name.endswith("_ddot") and len(name) > 5:
        return _accent(r"\ddot", name_latex(name[:-5]))
    if name.endswith("_dot") and len(name) > 4:
        return _accent(r"\dot", name_latex(name[:-4]))
    if name.startswith("p_") and len(name) > 2:
        return rf"p_{{{name_latex(name[2:])}}}"
    match = _MULTIPLIER.match(name)
    if match:
        return rf"\lambda_{{{match.group(1)}}}"
    return sp.latex(sp.Symbol(name))


def free_letter(candidates, used) -> str:
    r"""The first of ``candidates`` (LaTeX letters) that no printed name in ``used`` shows:
    a name's LaTeX shows ``\phi`` when the command appears in it (``\phi``,
    ``\phi_{1}``, ``\dot{\phi}``), not when it is part of another (``\varphi``).

    The last candidate should be one no name prints (:func:`name_latex` never gives
    ``\mathsf``): it is taken when all the others are shown.

    >>> free_letter([r"\phi", r"\varphi", r"\mathsf{c}"], {r"\dot{\phi}", "x"})
    '\\varphi'
    """
    for c in candidates:
        pattern = re.compile(re.escape(c) + r"(?![A-Za-z])")
        if not any(pattern.search(u) for u in used):
            return c
    return candidates[-1]


def _accent(accent: str, base: str) -> str:
    """The accent over the symbol, not over its subscript or superscript:
    ``\\dot{q}_{1}`` for q1, ``\\dot{\\theta}_{2}`` for theta2."""
    depth = 0
    for i, ch in enumerate(base):
        depth += {"{": 1, "}": -1}.get(ch, 0)
        if depth == 0 and ch in "_^" and i > 0:
            return f"{accent}{{{base[:i]}}}{base[i:]}"
    return f"{accent}{{{base}}}"


def latex(expr) -> str:
    """LaTeX of an expression, every symbol printed by :func:`name_latex`."""
    expr = sp.sympify(expr)
    names = {s: name_latex(s.name) for s in expr.free_symbols if isinstance(s, sp.Symbol)}
    return sp.latex(expr, symbol_names=names)


def matrix_latex(rows) -> str:
    """A matrix (sympy Matrix or nested lists of expressions) as a bmatrix."""
    M = sp.Matrix(rows)
    if M.rows == 0 or M.cols == 0:
        return r"\begin{bmatrix}\end{bmatrix}"
    body = r" \\ ".join(" & ".join(latex(M[i, j]) for j in range(M.cols)) for i in range(M.rows))
    return r"\begin{bmatrix}" + body + r"\end{bmatrix}"


def text(words: str) -> str:
    r"""Plain words inside math mode (``\text{...}``, underscores escaped)."""
    return r"\text{" + words.replace("\\", "").replace("_", r"\_").replace("&", r"\&") \
        .replace("%", r"\%").replace("#", r"\#") + "}"


def aligned(rows) -> str:
    """``(left, right)`` pairs as an ``aligned`` block (``left &= right``).

    A row whose right side is None is a line of its own, set from the alignment
    point (``& left``): every row has its ``&``.
    """
    lines = []
    for left, right in rows:
        lines.append(f"& {left}" if right is None else f"{left} &= {right}")
    return "\\begin{aligned}\n" + " \\\\\n".join(lines) + "\n\\end{aligned}"
