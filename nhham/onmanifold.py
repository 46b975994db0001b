"""Deciding things "on M_k": exact reduction first, seeded sampling second.

A :class:`Submanifold` of TQ is the zero set of a list of constraint
expressions in (q, v) (affine velocity constraints, holonomic constraints,
secondary constraints of any form). To decide whether a function vanishes on
it, or the rank of a matrix of functions on it, nhham

1. eliminates variables exactly: coordinates that a constraint gives linearly
   with a constant coefficient (``q1 = 0``), then dependent velocities from
   the affine constraints, choosing the velocity set whose block of mu is best
   conditioned at sampled points (not simply the first columns);
2. cancels rationally, and where sines and cosines remain reduces modulo
   sin^2 + cos^2 - 1 (and modulo any polynomial constraints that could not be
   eliminated) with a Groebner-basis remainder;
3. otherwise evaluates at seeded random points of the submanifold found by
   Newton projection, in float64 or in mpmath with the requested digits.

Every answer is a :class:`Decision` that records how it was reached.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Sequence

import mpmath
import numpy as np
import sympy as sp

from .errors import ComputationError

__all__ = ["Decision", "Submanifold"]


@dataclass(frozen=True)
class Decision:
    """How a vanishing or rank question on a submanifold was answered.

    Attributes
    ----------
    value : bool or int
        ``True``/``False`` for "vanishes on M", or the rank for rank questions.
    method : {"exact", "sampled"}
        Exact reduction, or evaluation at sample points.
    detail : str
        Human-readable evidence.
    precision : str
        ``"exact"``, ``"float64"`` or ``"mpmath:<digits>"``.
    samples : int
        Number of sample points used (0 for exact decisions).
    max_abs : float or None
        Largest absolute value found at the samples (vanishing questions).
    singular_values : tuple of tuple of float
        Singular values at each sample (rank questions).
    point_residual : float or None
        Largest constraint residual of the sample points.
    warnings : tuple of str
        Reasons to distrust the answer (rank not constant, values near the
        tolerance).
    """

    value: object
    method: str
    detail: str
    precision: str = "exact"
    samples: int = 0
    max_abs: float | None = None
    singular_values: tuple = ()
    point_residual: float | None = None
    warnings: tuple = ()

    def __bool__(self):
        return bool(self.value)

    def describe(self) -> str:
        """One line saying what was decided and how."""
        text = f"{self.value} ({self.method}, {self.precision}): {self.detail}"
        if self.warnings:
            text += " WARNING: " + "; ".join(self.warnings)
        return text


@dataclass(frozen=True)
class Reduction:
    """An exact partial solution of the constraint equations.

    Attributes
    ----------
    substitution : dict
        Solved variable -> expression in the remaining variables.
    residual : tuple of sympy.Expr
        Equations that could not be eliminated (reduced by the substitution).
    """

    substitution: dict
    residual: tuple


class Submanifold:
    """The zero set M of constraint expressions in TQ.

    Parameters
    ----------
    system : nhham.System
        Supplies coordinates, velocities, parameters and their values.
    equations : sequence of sympy.Expr
        The constraints defining M (each = 0).
    precision : int or None, optional
        ``None`` for float64 sampling; an integer for mpmath with that many
        significant digits (slower, more reliable near singular cases).
    samples : int, optional
        Number of seeded sample points for sampled decisions.
    seed : int, optional
        Seed of the sample points (decisions are reproducible).
    fibre : sequence of sympy.Symbol, optional
        The fibre variables: the velocities (default, M in TQ) or the
        momenta (M in T*Q). The variables are coordinates + fibre.
    """

    def __init__(self, system, equations: Sequence[sp.Expr], precision: int | None = None,
                 samples: int = 6, seed: int = 1996, fibre: Sequence[sp.Symbol] | None = None):
        self.system = system
        self.equations = tuple(sp.sympify(e) for e in equations)
        self.precision = precision
        self.samples = samples
        self.seed = seed
        self.fibre = tuple(system.velocities if fibre is None else fibre)
        self.variables = tuple(system.coordinates) + self.fibre

    @property
    def precision_label(self) -> str:
        return "float64" if self.precision is None else f"mpmath:{self.precision}"

    # ---------------------------------------------------------- reduction
    @cached_property
    def reduction(self) -> Reduction:
        """Exact elimination of coordinates and dependent velocities."""
        sub: dict = {}
        pending = [e for e in self.equations]
        coords = list(self.system.coordinates)
        vels = set(self.fibre)
        # Coordinates given linearly with a constant coefficient, repeatedly.
        progress = True
        while progress:
            progress = False
            for eq in list(pending):
                e = sp.expand(eq.xreplace(sub)) if sub else sp.expand(eq)
                if e == 0:
                    pending.remove(eq)
                    progress = True
                    continue
                if e.free_symbols & vels:
                    continue
                for q in coords:
                    if q in sub or q not in e.free_symbols:
                        continue
                    coeff = e.coeff(q, 1)
                    if coeff.free_symbols or coeff == 0 or sp.expand(e - coeff * q).has(q):
                        continue
                    value = sp.expand(-(e - coeff * q) / coeff)
                    sub = {k: sp.expand(v.xreplace({q: value})) for k, v in sub.items()}
                    sub[q] = value
                    pending.remove(eq)
                    progress = True
                    break
                if progress:
                    break
        pending = [sp.expand(e.xreplace(sub)) for e in pending]
        pending = [e for e in pending if e != 0]
        affine = [e for e in pending if _is_affine(e, self.fibre) and e.free_symbols & vels]
        rest = [e for e in pending if e not in affine]
        vsub, leftover = self._solve_velocities(affine, sub)
        sub.update(vsub)
        residual = tuple(
            r for r in (_cancel(e.xreplace(sub)) for e in rest + leftover) if r != 0
        )
        return Reduction(substitution=sub, residual=residual)

    def _solve_velocities(self, affine, qsub):
        """Solve independent affine rows for a well-conditioned velocity set."""
        if not affine:
            return {}, []
        vels = list(self.fibre)
        mu = sp.Matrix([[sp.diff(e, v) for v in vels] for e in affine])
        rest = sp.Matrix([e.xreplace({v: 0 for v in vels}) for e in affine])
        samples = [self._numeric_matrix(mu, pt) for pt in self._raw_points(4)]
        rows = _independent_rows(samples)
        cols = _best_columns([S[rows] for S in samples])
        if cols is None:
            return {}, affine
        dep = [vels[c] for c in cols]
        free = [v for v in vels if v not in dep]
        block = mu.extract(rows, cols)
        rhs = -(mu.extract(rows, [vels.index(v) for v in free]) * sp.Matrix(free)
                + rest.extract(rows, [0])) if free else -rest.extract(rows, [0])
        sol = _solve_small(block, rhs)
        vsub = {v: _cancel(s) for v, s in zip(dep, sol)}
        leftover = [affine[i] for i in range(len(affine)) if i not in rows]
        return vsub, leftover

    def reduce(self, expr) -> sp.Expr:
        """``expr`` with solved variables substituted and rationally cancelled."""
        red = self.reduction
        return _cancel(sp.sympify(expr).xreplace(red.substitution))

    # ------------------------------------------------------------ decisions
    def vanishes(self, expr, tol: float | None = None) -> Decision:
        """Decide whether ``expr`` vanishes identically on M.

        Parameters
        ----------
        expr : sympy.Expr
            A function of (q, v) and parameters.
        tol : float, optional
            Relative tolerance of the sampled test; default 1e-9 for float64
            and 10**(3 - digits) for mpmath.
        """
        reduced = self.reduce(expr)
        if reduced == 0:
            return Decision(True, "exact", "vanishes after exact reduction")
        if _vanishes_modulo(reduced, self.reduction.residual, self.variables):
            return Decision(True, "exact",
                            "vanishes modulo sin^2+cos^2=1 and the remaining constraints")
        return self._sampled_vanishes(reduced, tol)

    def rank(self, matrix: sp.Matrix, tol: float | None = None) -> Decision:
        """Decide the rank of a matrix of functions on M (generic rank).

        Exact when every entry reduces to a number; otherwise the rank at
        seeded sample points from singular values, with a warning where it
        is not the same at every point.
        """
        matrix = sp.Matrix(matrix)
        if 0 in matrix.shape:
            return Decision(0, "exact", "empty matrix")
        reduced = matrix.applyfunc(self.reduce)
        if not reduced.free_symbols:
            r = reduced.rank()
            return Decision(r, "exact", f"entries reduce to numbers; rank {r}")
        exact_full = self._exact_full_rank(reduced)
        if exact_full is not None:
            return exact_full
        points, resid = self.points()
        f = self._lambdify([reduced])
        svals, ranks = [], []
        tol = self._tol(tol)
        for pt in points:
            S = np.array(self._evaluate(f, pt)[0], dtype=object)
            s = _singular_values(S, self.precision)
            svals.append(tuple(float(x) for x in s))
            top = max(float(s[0]) if len(s) else 0.0, 1e-300)
            ranks.append(int(sum(float(x) > tol * max(top, 1.0) for x in s)))
        r = max(ranks)
        warnings = []
        if len(set(ranks)) > 1:
            warnings.append(f"rank is not constant on M: ranks {ranks} at the samples")
        gaps = [sv[r - 1] / max(sv[0], 1e-300) for sv in svals if r >= 1]
        if gaps and min(gaps) < 1e3 * tol:
            warnings.append(
                f"smallest kept singular value ratio {min(gaps):.3g} is within 1e3 of the "
                f"tolerance {tol:g}: the rank is doubtful at this precision"
            )
        return Decision(
            r, "sampled",
            f"rank {r} at {len(points)} seeded points (relative tolerance {tol:g})",
            precision=self.precision_label, samples=len(points), singular_values=tuple(svals),
            point_residual=resid, warnings=tuple(warnings),
        )

    def _exact_full_rank(self, reduced):
        """Full rank proved exactly: a maximal minor is a nonzero function on M.

        Only for small matrices and when the reduction parametrises M
        completely (no residual equations), so that a nonzero reduced
        expression is a nonzero function on M.
        """
        k = min(reduced.shape)
        if k > 6 or self.reduction.residual:
            return None
        square = reduced if reduced.rows == reduced.cols else (
            reduced * reduced.T if reduced.rows < reduced.cols else reduced.T * reduced)
        det = _cancel(square.det(method="berkowitz"))
        if det == 0 or _vanishes_modulo(det, (), self.variables):
            return None
        return Decision(k, "exact", f"full rank {k}: the determinant reduces to the nonzero "
                                    f"function {_short(det)} on M")

    # ------------------------------------------------------------ sampling
    def points(self):
        """Seeded sample points on M as a list of substitution dicts.

        Returns
        -------
        points : list of dict
            Symbol -> number (float, or mpmath.mpf at higher precision),
            covering coordinates, velocities and parameters.
        residual : float
            Largest constraint residual over the points.
        """
        return self._points

    @cached_property
    def _points(self):
        pts, worst = [], 0.0
        attempts = 0
        eqs = list(self.equations)
        for raw in self._raw_points(self.samples * 4):
            if len(pts) == self.samples:
                break
            attempts += 1
            try:
                pt, res = self._project(raw, eqs)
            except (ZeroDivisionError, ValueError, OverflowError, ArithmeticError,
                    np.linalg.LinAlgError):
                continue
            if res is None:
                continue
            pts.append(pt)
            worst = max(worst, res)
        if not pts:
            raise ComputationError(
                f"could not find points on the submanifold defined by {list(self.equations)} "
                f"(Newton projection failed from {attempts} seeded starts; it may be empty)"
            )
        return pts, worst

    def _raw_points(self, count):
        rng = np.random.default_rng(self.seed)
        syms = self.variables
        out = []
        for _ in range(count):
            pt = {s: float(rng.uniform(-1.3, 1.3)) for s in syms}
            for p in self.system.parameters:
                pt[p] = self.system.parameter_values.get(p, float(rng.uniform(0.6, 1.7)))
            out.append(pt)
        return out

    def _project(self, raw, eqs):
        """Newton projection (minimum-norm steps) of a point onto M."""
        syms = list(self.variables)
        if not eqs:
            return self._convert(raw), 0.0
        F, J = self._residual_functions(tuple(eqs))
        params = [raw[p] for p in self.system.parameters]
        z = [raw[s] for s in syms]
        if self.precision is None:
            z = np.array(z, dtype=float)
            for _ in range(60):
                r = np.array(F(*z, *params), dtype=float).ravel()
                if not np.all(np.isfinite(r)):
                    return None, None
                if np.max(np.abs(r)) < 1e-14 * (1 + np.max(np.abs(z))):
                    break
                Jz = np.array(J(*z, *params), dtype=float)
                z = z - np.linalg.lstsq(Jz, r, rcond=None)[0]
            r = np.array(F(*z, *params), dtype=float).ravel()
            res = float(np.max(np.abs(r)))
            if not np.isfinite(res) or res > 1e-10 * (1 + float(np.max(np.abs(z)))):
                return None, None
            pt = dict(zip(syms, map(float, z)))
            pt.update({p: float(raw[p]) for p in self.system.parameters})
            return pt, res
        with mpmath.workdps(self.precision + 10):
            z = mpmath.matrix([mpmath.mpf(x) for x in z])
            params = [mpmath.mpf(x) for x in params]
            target = mpmath.mpf(10) ** (-(self.precision + 5))
            for _ in range(80):
                r = mpmath.matrix(F(*z, *params))
                if mpmath.norm(r, mpmath.inf) < target * (1 + mpmath.norm(z, mpmath.inf)):
                    break
                Jz = mpmath.matrix(J(*z, *params))
                # Minimum-norm step: dz = J^T (J J^T)^+ r.
                JJt = Jz * Jz.T
                try:
                    y = mpmath.lu_solve(JJt, r)
                except ZeroDivisionError:
                    y = mpmath.qr_solve(JJt, r)[0]
                z = z - Jz.T * y
            r = mpmath.matrix(F(*z, *params))
            res = mpmath.norm(r, mpmath.inf)
            if res > mpmath.mpf(10) ** (-self.precision) * (1 + mpmath.norm(z, mpmath.inf)):
                return None, None
            pt = dict(zip(syms, [z[i] for i in range(len(syms))]))
            pt.update({p: mpmath.mpf(raw[p]) for p in self.system.parameters})
            return pt, float(res)

    def _convert(self, raw):
        if self.precision is None:
            return dict(raw)
        with mpmath.workdps(self.precision + 10):
            return {k: mpmath.mpf(v) for k, v in raw.items()}

    @cached_property
    def _residual_cache(self):
        return {}

    def _residual_functions(self, eqs):
        if eqs not in self._residual_cache:
            syms = list(self.variables)
            args = syms + list(self.system.parameters)
            Fm = sp.Matrix(eqs)
            Jm = Fm.jacobian(syms)
            module = "numpy" if self.precision is None else "mpmath"
            self._residual_cache[eqs] = (
                sp.lambdify(args, Fm, modules=module), sp.lambdify(args, Jm, modules=module)
            )
        return self._residual_cache[eqs]

    def _lambdify(self, exprs):
        args = list(self.variables + self.system.parameters)
        module = "numpy" if self.precision is None else "mpmath"
        return sp.lambdify(args, exprs, modules=module)

    def _evaluate(self, f, pt):
        args = [pt[s] for s in self.variables
                + self.system.parameters]
        if self.precision is None:
            with np.errstate(all="ignore"):
                return f(*args)
        with mpmath.workdps(self.precision):
            return f(*args)

    def _numeric_matrix(self, M, pt):
        return np.array(M.xreplace(pt).evalf(), dtype=complex).real.astype(float)

    def _tol(self, tol):
        if tol is not None:
            return tol
        return 1e-9 if self.precision is None else 10.0 ** (3 - self.precision)

    def _sampled_vanishes(self, expr, tol):
        points, resid = self.points()
        tol = self._tol(tol)
        f = self._lambdify([expr])
        scale_f = self._lambdify([sum((abs(t) for t in sp.Add.make_args(sp.expand(expr))),
                                      sp.S.Zero)])
        worst, worst_rel = 0.0, 0.0
        for pt in points:
            value = self._evaluate(f, pt)[0]
            scale = self._evaluate(scale_f, pt)[0]
            a = abs(complex(value))
            if not math.isfinite(a):
                return Decision(False, "sampled", f"not finite at a sample point {pt}",
                                precision=self.precision_label, samples=len(points),
                                point_residual=resid)
            worst = max(worst, a)
            worst_rel = max(worst_rel, a / max(float(abs(scale)), 1.0))
        vanishes = worst_rel <= tol
        warnings = ()
        if not vanishes and worst_rel <= 1e3 * tol:
            warnings = (f"largest relative value {worst_rel:.3g} is within 1e3 of the "
                        f"tolerance {tol:g}: the answer is doubtful at this precision",)
        return Decision(
            vanishes, "sampled",
            f"largest |value| {worst:.3g} (relative {worst_rel:.3g}) at {len(points)} seeded "
            f"points, tolerance {tol:g}",
            precision=self.precision_label, samples=len(points), max_abs=worst,
            point_residual=resid, warnings=warnings,
        )


# ------------------------------------------------------------------ helpers
def _cancel(expr):
    expr = sp.sympify(expr)
    if expr.is_number:
        return expr
    try:
        return sp.cancel(sp.together(sp.expand(expr)))
    except (sp.PolynomialError, TypeError):  # pragma: no cover - exotic functions
        return sp.expand(expr)


def _short(expr, limit=80):
    text = str(expr)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _is_affine(expr, vels):
    vset = set(vels)
    return all(not sp.diff(expr, v).free_symbols & vset for v in vels)


def _independent_rows(samples):
    """Indices of rows independent at the sample points (greedy)."""
    rows = []
    for i in range(samples[0].shape[0]):
        trial = rows + [i]
        if max(np.linalg.matrix_rank(S[trial], tol=1e-9 * max(1.0, np.abs(S).max()))
               for S in samples) == len(trial):
            rows.append(i)
    return rows


def _best_columns(samples):
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


def _solve_small(block, rhs):
    """Solve block x = rhs symbolically (small, usually triangular or constant)."""
    if not block.free_symbols and block.is_diagonal():
        return [rhs[i] / block[i, i] for i in range(block.rows)]
    return list(block.LUsolve(rhs))


def _vanishes_modulo(expr, residual, gens):
    """Exact test: numerator of ``expr`` reduces to 0 modulo trig and polynomial relations."""
    try:
        num = sp.numer(sp.together(sp.expand_trig(expr)))
    except Exception:  # pragma: no cover
        return False
    trig = sorted(num.atoms(sp.sin, sp.cos), key=sp.default_sort_key)
    args = sorted({t.args[0] for t in trig}, key=sp.default_sort_key)
    if not args and not residual:
        return False
    rel, rep = [], {}
    for a in args:
        if not a.is_Symbol:
            return False
        s, c = sp.Dummy(f"s_{a}"), sp.Dummy(f"c_{a}")
        rep[sp.sin(a)], rep[sp.cos(a)] = s, c
        rel.append(s ** 2 + c ** 2 - 1)
    num = sp.expand(num.xreplace(rep))
    extra = []
    for r in residual:
        rn = sp.numer(sp.together(sp.expand_trig(r))).xreplace(rep)
        extra.append(sp.expand(rn))
    polys = rel + extra
    variables = sorted(num.free_symbols | set().union(*[p.free_symbols for p in polys]),
                       key=sp.default_sort_key)
    try:
        for p in polys + [num]:
            sp.Poly(p, *variables)  # raises when p is not polynomial in the variables
        basis = sp.groebner(polys, *variables, order="grevlex")
        _, remainder = sp.reduced(num, list(basis), *variables, order="grevlex")
    except (sp.PolynomialError, sp.polys.polyerrors.PolificationFailed, TypeError, ValueError,
            sp.polys.polyerrors.CoercionFailed):
        return False
    return sp.expand(remainder) == 0


def _singular_values(S, precision):
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
