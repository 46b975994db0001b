"""Ranks and vanishing decided at sampled (float64 or mpmath) points of M_k.

Singular values of equilibrated samples, counted above a noise floor set by the
points' residual and the values' scale; the zero test of an expression reduced on M_k;
the best-conditioned regular block. Used by
:class:`nhham.lagrangian.submanifold.Submanifold` where no exact route decides.
"""

from __future__ import annotations

import itertools
import math

import mpmath
import numpy as np
import sympy as sp

from nhham.errors import BudgetExceeded, InputError
from nhham.lagrangian.decision import Decision
from nhham.settings import STATE_BOX, Precision
from nhham.system.expressions import short

__all__ = [
    "value_scale",
    "count_above",
    "relative_singular_values",
    "equilibrated",
    "without_noise",
    "record",
    "is_affine",
    "independent_rows",
    "best_columns",
    "zero_test",
    "best_block",
    "singular_values",
    "is_finite",
    "nowhere_finite",
    "rank_from_values",
]


# ------------------------------------------------------------------ helpers
def value_scale(expr, variables):
    """The size a value of ``expr`` at a sample point is compared with.

    The expression with every sum replaced by the sum of the sizes of its terms (so no
    cancellation can make it small), every state variable z by |z| + the half-width of
    the sample box, and every function of the state by 1 + its modulus: a bound on the
    terms of ``expr`` over a neighbourhood of the point, formed on the tree as it is
    (no expansion). Unit-free, since it scales with the parameters as ``expr`` does, and
    a function vanishing on M stays zero at a point off M by the rounding of the Newton
    projection (q1 = 4e-16 on {q1 = 0} is 4e-16 of its size 1.3).
    """
    state = set(variables)
    box = max(abs(b) for b in STATE_BOX)
    memo: dict = {}

    def modulus(e):  # unevaluated: sympy's Abs would query assumptions on large trees
        return sp.Abs(e, evaluate=False)

    def size(e):
        if e in memo:
            return memo[e]
        if e.is_number:
            out = abs(e)
        elif e.is_Symbol:
            out = sp.Add(modulus(e), box, evaluate=False) if e in state else modulus(e)
        elif e.is_Add:
            out = sp.Add(*[size(a) for a in e.args], evaluate=False)
        elif e.is_Mul:
            out = sp.Mul(*[size(a) for a in e.args], evaluate=False)
        elif e.is_Pow and e.exp.is_number and e.exp > 0:
            out = sp.Pow(size(e.base), e.exp, evaluate=False)
        elif e.free_symbols & state:
            # a function of the state (or a denominator): its modulus, at least 1
            out = sp.Add(1, modulus(e), evaluate=False)
        else:
            out = modulus(e)
        memo[e] = out
        return out

    return size(sp.sympify(expr))


def count_above(singular_values, threshold) -> int:
    return int(sum(float(x) > threshold for x in singular_values))


def relative_singular_values(singular_values, floor=0.0) -> tuple:
    """Singular values over the largest (at least ``floor``)."""
    top = max(float(singular_values[0]) if len(singular_values) else 0.0, floor)
    return tuple(float(x) / top for x in singular_values) if top else \
        tuple(0.0 for _ in singular_values)


def equilibrated(S):
    """S with rows and columns scaled to unit largest modulus (Ruiz's iteration); zero
    rows and columns stay zero. Works on float and on object (mpf) arrays."""
    A = np.array(S, dtype=object if np.asarray(S).dtype == object else complex)
    for _ in range(8):
        for axis in (1, 0):
            big = [max((abs(x) for x in (A[i, :] if axis else A[:, i])), default=0)
                   for i in range(A.shape[0] if axis else A.shape[1])]
            for i, b in enumerate(big):
                if b:
                    root = b ** 0.5
                    if axis:
                        A[i, :] = A[i, :] / root
                    else:
                        A[:, i] = A[:, i] / root
    return A


def without_noise(S, size, zero):
    """S with the entries below ``zero`` times their size set to 0."""
    A = np.array(S, dtype=object if np.asarray(S).dtype == object else complex)
    B = np.asarray(size)
    for idx in np.ndindex(A.shape):
        if abs(A[idx]) <= zero * abs(B[idx]):
            A[idx] = 0
    return A


def record(points, variables, limit=6):
    """Sample points as tuples of (name, float) for a Decision's record."""
    out = []
    for pt in points[:limit]:
        out.append(tuple((s.name, round(float(pt[s]), 12)) for s in variables))
    return tuple(out)


def is_affine(expr, vels):
    vset = set(vels)
    return all(not sp.diff(expr, v).free_symbols & vset for v in vels)


def is_finite(S) -> bool:
    """Whether every entry of a sampled matrix (floats, or mpmath numbers) is finite.

    >>> is_finite(np.array([[1.0, 2.0]])), is_finite(np.array([[1.0, np.nan]]))
    (True, False)
    """
    A = np.asarray(S)
    if A.dtype != object:
        return bool(np.all(np.isfinite(A)))
    return all(mpmath.isfinite(x) for x in A.flat)


def independent_rows(samples):
    """Indices of rows independent at the sample points (greedy)."""
    rows = []
    for i in range(samples[0].shape[0]):
        trial = rows + [i]
        if max(np.linalg.matrix_rank(S[trial], tol=1e-9 * max(1.0, np.abs(S).max()))
               for S in samples) == len(trial):
            rows.append(i)
    return rows


def best_columns(samples):
    """Column set of a k x n matrix whose k x k block is best conditioned.

    Scores every column subset (when there are few) by the worst ratio of
    smallest to largest singular value over the samples; ties go to blocks
    that are the same at every sample (often constant, so no division by a
    function of q appears).
    """
    k, n = samples[0].shape
    if k == 0:
        return None
    if math.comb(n, k) <= 400:
        candidates = itertools.combinations(range(n), k)
    else:
        import scipy.linalg

        candidates = {tuple(sorted(scipy.linalg.qr(S, pivoting=True)[2][:k])) for S in samples}
    best, best_score = None, -1.0
    for cols in candidates:
        blocks = [S[:, cols] for S in samples]
        ratios = []
        for B in blocks:
            s = np.linalg.svd(B, compute_uv=False)
            ratios.append(s[-1] / s[0] if s[0] > 0 else 0.0)
        constant = all(np.allclose(B, blocks[0], atol=1e-12) for B in blocks)
        score = min(ratios) + (1.0 if constant and min(ratios) > 1e-8 else 0.0)
        if score > best_score + 1e-12:
            best, best_score = cols, score
    if best_score <= 1e-10:
        return None
    return list(best)


def zero_test(expr, residual=(), parameters=(), values=None):
    """Exact zero test of a function on M given by its reduced expression.

    Sines and cosines of symbols (after ``expand_trig``) become new variables
    s, c with s^2 + c^2 = 1. The numerator must then be a polynomial in its
    symbols; anything else (exp, sqrt, trig of non-symbols) is undecided.

    Returns
    -------
    verdict : True, False or None
        True: the numerator lies in the ideal of the trig relations and the
        ``residual`` equations (it vanishes on M). False: only when there is
        no residual (the reduction parametrises M) and the numerator is not
        in the ideal of the trig relations, which is prime with a Zariski
        dense set of real points, so the function is nonzero on an open set.
        None: undecided.
    warning : str or None
        Set when the verdict is False but every coefficient of the numerator
        (as a polynomial in the state) vanishes at the given parameter values.
    """
    expr = sp.sympify(expr)
    if expr == 0:
        return True, None
    if expr.is_number:
        return (None, None) if expr.has(sp.nan, sp.zoo, sp.oo) else (False, None)
    try:
        num = sp.numer(sp.together(sp.expand_trig(expr)))
    except BudgetExceeded:  # an expiry is not an undecided vanishing
        raise
    except Exception:  # pragma: no cover - sympy failure on exotic input
        return None, None
    rep, rel = {}, []
    for atom in num.atoms(sp.Function):
        if not atom.free_symbols:
            continue
        if not isinstance(atom, (sp.sin, sp.cos)) or not atom.args[0].is_Symbol:
            return None, None
        a = atom.args[0]
        if sp.sin(a) not in rep:
            s, c = sp.Dummy(f"s_{a}"), sp.Dummy(f"c_{a}")
            rep[sp.sin(a)], rep[sp.cos(a)] = s, c
            rel.append(s ** 2 + c ** 2 - 1)
    num = sp.expand(num.xreplace(rep))
    extra = []
    for r in residual:
        try:
            rn = sp.numer(sp.together(sp.expand_trig(r)))
        except BudgetExceeded:
            raise
        except Exception:  # pragma: no cover
            return None, None
        for atom in rn.atoms(sp.Function):
            if atom.free_symbols and atom not in rep:
                return None, None
        extra.append(sp.expand(rn.xreplace(rep)))
    polys = rel + extra
    variables = sorted(num.free_symbols | set().union(*[p.free_symbols for p in polys]),
                       key=sp.default_sort_key)
    if not variables:
        return (num == 0), None
    try:
        for p in polys + [num]:
            if not p.is_polynomial(*variables):
                return None, None
        basis = sp.groebner(polys, *variables, order="grevlex") if extra else rel
        remainder = sp.reduced(num, list(basis), *variables, order="grevlex")[1] \
            if basis else num
    except (sp.PolynomialError, sp.polys.polyerrors.PolificationFailed, TypeError, ValueError,
            sp.polys.polyerrors.CoercionFailed):
        return None, None
    remainder = sp.expand(remainder)
    if remainder == 0:
        return True, None
    if extra:
        return None, None
    return False, _parameter_warning(remainder, parameters, values or {})


def _parameter_warning(poly_expr, parameters, values):
    """Warn when a polynomial nonzero in the parameters vanishes at their values.

    Decided exactly, with the values read as the decimals they were written as (every
    coefficient, as a polynomial in the state, is zero there): no tolerance, so the
    answer does not depend on the units.
    """
    params = [p for p in parameters if p in poly_expr.free_symbols]
    if not params or any(p not in values for p in params):
        return None
    state = sorted(poly_expr.free_symbols - set(params), key=sp.default_sort_key)
    try:
        coeffs = sp.Poly(poly_expr, *state).coeffs() if state else [poly_expr]
    except sp.PolynomialError:  # pragma: no cover
        return None
    at = {p: sp.Rational(repr(float(values[p]))) for p in params}
    if all(sp.expand(sp.sympify(c).xreplace(at)) == 0 for c in coeffs):
        return (f"the nonzero function {short(poly_expr)} vanishes at the given parameter "
                f"values (exact decisions treat parameters as generic)")
    return None


def best_block(samples, r):
    """(rows, cols, score) of the best r x r block over numeric samples.

    The score of a block B of A is the worst over the samples of
    sigma_min(B) / ||A||_2, doubled for a block that is the same at every sample.
    """
    R, K = samples[0].shape
    row_sets = list(itertools.combinations(range(R), r))
    col_sets = list(itertools.combinations(range(K), r))
    if len(row_sets) * len(col_sets) > 400:
        import scipy.linalg

        col_sets = {tuple(sorted(scipy.linalg.qr(S, pivoting=True)[2][:r])) for S in samples}
        pairs = set()
        for cols in col_sets:
            for S in samples:
                rows = tuple(sorted(scipy.linalg.qr(S[:, cols].T, pivoting=True)[2][:r]))
                pairs.add((rows, cols))
        candidates = sorted(pairs)
    else:
        candidates = [(rows, cols) for rows in row_sets for cols in col_sets]
    norms = [max(np.linalg.norm(S, 2), 1e-300) for S in samples]
    best, best_score, best_raw = None, -1.0, 0.0
    for rows, cols in candidates:
        blocks = [S[np.ix_(rows, cols)] for S in samples]
        # sigma_min(B) / ||A||: small when B is ill-conditioned *or* small compared
        # with the matrix (for 1 x 1 blocks this prefers the largest entry).
        ratios = [np.linalg.svd(B, compute_uv=False)[-1] / nrm for B, nrm in zip(blocks, norms)]
        raw = min(ratios)
        constant = all(np.allclose(B, blocks[0], rtol=1e-12, atol=1e-14) for B in blocks)
        score = raw * (2.0 if constant and len(blocks) > 1 else 1.0)
        if score > best_score * (1 + 1e-9) + 1e-15:
            best, best_score, best_raw = (list(rows), list(cols)), score, raw
    if best is None or best_raw <= 1e-14:
        return None, None, 0.0
    return best[0], best[1], best_raw


def singular_values(S, precision):
    if precision is None:
        A = np.array(S, dtype=complex)
        if np.allclose(A.imag, 0):
            A = A.real.astype(float)
        return np.linalg.svd(A, compute_uv=False)
    with mpmath.workdps(precision):
        A = mpmath.matrix([[mpmath.mpmathify(x) for x in row] for row in S])
        s = mpmath.svd_r(A, compute_uv=False) if A.rows and A.cols else []
        vals = sorted((abs(x) for x in s), reverse=True)
        return vals


def nowhere_finite(M, value, count) -> InputError:
    """The InputError that an entry of the matrix M is not finite at any of the ``count``
    sample points of a constraint set (``value``: M at the first of them), naming it."""
    entry = next(e for e, x in zip(M, np.asarray(value).flat) if not is_finite(np.array([x])))
    return InputError(f"{short(entry, 80)} is not finite at any of {count} points of the "
                      f"constraint set (an overflow, or a function outside its domain: the "
                      f"Lagrangian's W or a constraint is singular there); nhham needs them "
                      f"defined on M_1")


def rank_from_values(values, points, variables, resid, tol, zero, precision, sizes,
                     skipped=0) -> Decision:
    """The rank of a matrix from its values at sample points, whatever the units.

    Parameters
    ----------
    values : list of arrays, each (r, c)
        The matrix at each point (finite), float64 or mpmath numbers.
    points : list of dict
        The points (for the record); ``variables``: their coordinates and velocities.
    resid : float
        The points' constraint residual.
    tol, zero : float
        The rank tolerance and the level below which a value is rounding noise.
    precision : int or None
        float64 (None) or mpmath digits.
    sizes : callable
        ``sizes()``: the entries' sizes at the points (:func:`value_scale`), asked only
        when rounding noise may need to be set to 0.
    skipped : int
        The points left out, where the matrix is not finite (said in the warnings).
    """
    plain = [singular_values(S, precision) for S in values]
    ranks = [count_above(s, tol * max(float(s[0]) if len(s) else 0.0, 1.0)) for s in plain]
    relative = [relative_singular_values(singular_values(equilibrated(S), precision))
                for S in values]
    how = "plain"
    if [count_above(s, tol) for s in relative] != ranks:
        cleaned = [without_noise(S, size, zero) for S, size in zip(values, sizes())]
        relative = [relative_singular_values(singular_values(equilibrated(S), precision))
                    for S in cleaned]
        ranks = [count_above(s, tol) for s in relative]
        how = "equilibrated"
    else:
        relative = [relative_singular_values(s, floor=1.0) for s in plain]
    r = max(ranks)
    warnings = []
    if skipped:
        warnings.append(f"{skipped} sample point(s) skipped: the matrix is not finite there")
    if len(set(ranks)) > 1:
        warnings.append(f"rank is not constant on M: ranks {ranks} at the samples")
    gaps = [sv[r - 1] for sv in relative if r >= 1]
    if gaps and min(gaps) < 1e3 * tol:
        warnings.append(
            f"smallest kept singular value ratio {min(gaps):.3g} is within 1e3 of the "
            f"tolerance {tol:g}: the rank is doubtful at this precision"
        )
    dropped = [sv[r] for sv in relative if r < len(sv)]
    if dropped and max(dropped) > zero:
        warnings.append(
            f"largest dropped singular value ratio {max(dropped):.3g} is above the zero "
            f"level {zero:.3g} but below the tolerance {tol:g}: near-singular at this "
            f"precision, the rank may be higher (try more digits)"
        )
    basis = ("relative tolerance" if how == "plain" else
             "singular values of the matrix equilibrated by rows and columns, rounding "
             "noise removed; relative tolerance")
    return Decision(
        r, "sampled", f"rank {r} at {len(points)} seeded points ({basis} {tol:g})",
        precision=Precision(precision).label, samples=len(points),
        singular_values=tuple(tuple(float(x) for x in s) for s in plain),
        point_residual=resid, warnings=tuple(warnings), points=record(points, variables),
    )


def real_domain(L, args):
    """``inside(point) -> bool``: L finite and real at the point (a dict over ``args``),
    when L has a function real on part of the reals only (a non-integer power, a
    logarithm, asin, acos, acosh, atanh: the square-root particle's sqrt(x0'^2 - |x'|^2));
    None when it has none (every point is inside). Sample points of TQ are drawn inside."""
    if not any((e.is_Pow and not e.exp.is_Integer and e.exp.is_number)
               or e.func in (sp.log, sp.asin, sp.acos, sp.acosh, sp.atanh)
               for e in sp.preorder_traversal(L)):
        return None
    from nhham.system.evaluation import numeric_function

    f = numeric_function(args, L)

    def inside(pt) -> bool:
        with np.errstate(all="ignore"):
            try:
                value = complex(f(*[float(pt[s]) for s in args]))
            except (ValueError, TypeError, ZeroDivisionError, OverflowError):
                return False
        return bool(np.isfinite(value.real) and value.imag == 0.0)
    return inside
