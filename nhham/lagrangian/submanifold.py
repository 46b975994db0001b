"""Deciding things "on M_k": exact reduction first, seeded sampling second.

A :class:`Submanifold` is the zero set of a list of constraint expressions
in the coordinates and a fibre: (q, v) on TQ (default), (q, p) on T*Q
(``fibre=momenta``) or q alone on Q (``fibre=()``); the constraints may be
affine velocity constraints, holonomic constraints or secondary constraints of
any form. To decide whether a function vanishes on it, or the rank of a matrix
of functions on it (:meth:`Submanifold.vanishes`, :meth:`Submanifold.rank`,
and :meth:`Submanifold.regular_block` for a well-conditioned regular block),
nhham

1. eliminates variables exactly: coordinates that a constraint gives linearly
   with a constant coefficient (``q1 = 0``), then dependent velocities from
   the affine constraints, choosing the velocity set whose block of mu is best
   conditioned at sampled points (not simply the first columns);
2. cancels rationally, and where sines and cosines remain reduces modulo
   sin^2 + cos^2 - 1 (and modulo any polynomial constraints that could not be
   eliminated) with a Groebner-basis remainder;
3. otherwise evaluates at seeded random points of the submanifold found by
   Newton projection, in float64 or in mpmath with the requested digits.

Every answer is a :class:`Decision` that records how it was reached. With
``exact=False`` steps 1-2 are skipped for decisions (sampling only), which is
how the two routes are compared.

What "exact" means. An exact decision is a proof for *generic* values of the
symbolic parameters (they are treated as indeterminates): "vanishes" means the
reduced expression is zero as a function (rational cancellation, or a Groebner
remainder modulo sin^2 + cos^2 = 1 and the constraints that could not be
eliminated); "does not vanish" is claimed exactly only when the reduction
parametrises M completely and the reduced expression is a nonzero polynomial
or rational function of the remaining variables and of sines and cosines of
them (such a function cannot vanish on an open set). Where a decisive nonzero
expression happens to vanish at the *given* parameter values, the decision
carries a warning.

What "sampled" means. Values at seeded points of M found by Newton
projection, in float64 (relative tolerance 1e-9) or mpmath with ``digits``
(relative tolerance 10**(3 - digits)). A quantity is *clearly zero* below the
zero level (1e-12 in float64, 10**(1 - digits) in mpmath, and never below
100 times the residual of the points) and *clearly nonzero* above 1e3 times
the tolerance; in between the decision is doubtful and says so in
``Decision.warnings`` instead of choosing silently.
"""

from __future__ import annotations

import contextlib
import functools
import math
from dataclasses import dataclass
from functools import cached_property
from typing import Sequence

import mpmath
import numpy as np
import sympy as sp

from nhham.errors import ComputationError, EmptySubmanifoldError
from nhham.lagrangian.algebra import (cancel, defined_where, solve_for_coordinates,
                                      solve_linear)
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.engine import Policy, decide
from nhham.lagrangian.quantities import Rank, Vanishing
from nhham.lagrangian.sampled import (
    best_block,
    best_columns,
    independent_rows,
    is_finite,
    is_affine,
    nowhere_finite,
    rank_from_values,
    real_domain,
    record,
    value_scale,
    zero_test,
)
from nhham.settings import PARAMETER_BOX, SEED, STATE_BOX, Precision
from nhham.system.evaluation import numeric_function
from nhham.system.velocities import velocity_free_part

__all__ = ["Submanifold", "has_real_point"]


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
        ``None`` for float64 sampling; an integer for mpmath with that many digits.
    samples, seed : int, optional
        Number and seed of the sample points of sampled decisions (reproducible).
    fibre : sequence of sympy.Symbol, optional
        The fibre variables: the velocities (default, M in TQ) or the
        momenta (M in T*Q), or ``()`` for a submanifold of Q. The variables
        are coordinates + fibre.
    exact : bool, optional
        If False, :meth:`vanishes` and :meth:`rank` skip the exact reduction
        and decide at sample points only (the reduction itself stays
        available through :meth:`reduce`).

    Examples
    --------
    >>> import sympy as sp
    >>> from nhham import Submanifold, System
    >>> x_dot, y_dot = sp.symbols("x_dot y_dot")
    >>> M = Submanifold(System(["x", "y"], "(x_dot**2 + y_dot**2)/2"), [y_dot])
    >>> M.vanishes(y_dot**2).value, M.vanishes(x_dot).value, M.rank(sp.Matrix([[y_dot, 1]])).value
    (True, False, 1)
    """

    def __init__(self, system, equations: Sequence[sp.Expr], precision: int | None = None,
                 samples: int = 6, seed: int = SEED, fibre: Sequence[sp.Symbol] | None = None,
                 exact: bool = True):
        self.system = system
        self.equations = tuple(sp.sympify(e) for e in equations)
        self.precision = precision
        self.samples = samples
        self.seed = seed
        self.fibre = tuple(system.velocities if fibre is None else fibre)
        self.variables = tuple(system.coordinates) + self.fibre
        self.exact = bool(exact)

    def with_equations(self, equations: Sequence[sp.Expr], samples: int | None = None
                       ) -> "Submanifold":
        """A Submanifold of the same space and settings with other equations.

        Parameters
        ----------
        equations : sequence of sympy.Expr
            The constraints of the new submanifold (each = 0).
        samples : int, optional
            Number of sample points (default: this manifold's).
        """
        return Submanifold(self.system, equations, precision=self.precision,
                           samples=self.samples if samples is None else samples,
                           seed=self.seed, fibre=self.fibre, exact=self.exact)

    def sampled_only(self) -> "Submanifold":
        """The same M deciding at sample points only (``exact=False``)."""
        if not self.exact:
            return self
        return Submanifold(self.system, self.equations, precision=self.precision,
                           samples=self.samples, seed=self.seed, fibre=self.fibre, exact=False)

    @property
    def precision_label(self) -> str:
        return Precision(self.precision).label

    # ---------------------------------------------------------- reduction
    @cached_property
    def reduction(self) -> Reduction:
        """Exact elimination of coordinates and dependent velocities."""
        vels = set(self.fibre)
        # Coordinates given linearly with a constant coefficient, repeatedly.
        sub, pending = solve_for_coordinates(self.system.coordinates, self.equations, vels)
        pending = [defined_where(e, sp.expand(e.xreplace(sub)), sub) for e in pending]
        pending = [e for e in pending if e != 0]
        affine = [e for e in pending if is_affine(e, self.fibre) and e.free_symbols & vels]
        rest = [e for e in pending if e not in affine]
        vsub, leftover = self._solve_velocities(affine, sub)
        sub.update(vsub)
        residual = tuple(
            r for r in (cancel(e.xreplace(sub)) for e in rest + leftover) if r != 0
        )
        return Reduction(substitution=sub, residual=residual)

    def _solve_velocities(self, affine, qsub):
        """Solve independent affine rows for a well-conditioned velocity set."""
        if not affine:
            return {}, []
        vels = list(self.fibre)
        mu = sp.Matrix([[sp.diff(e, v) for v in vels] for e in affine])
        rest = sp.Matrix([velocity_free_part(e, vels) for e in affine])
        # where a one-form is not finite (log(x) at x < 0) a point says nothing
        samples = [S for S in (self._numeric_matrix(mu, pt) for pt in self._raw_points(4))
                   if is_finite(S)]
        if not samples:
            return {}, affine
        rows = independent_rows(samples)
        cols = best_columns([S[rows] for S in samples])
        if cols is None:
            return {}, affine
        dep = [vels[c] for c in cols]
        free = [v for v in vels if v not in dep]
        block = mu.extract(rows, cols)
        rhs = -(mu.extract(rows, [vels.index(v) for v in free]) * sp.Matrix(free)
                + rest.extract(rows, [0])) if free else -rest.extract(rows, [0])
        sol = list(solve_linear(block, rhs))
        vsub = {v: cancel(s) for v, s in zip(dep, sol)}
        leftover = [affine[i] for i in range(len(affine)) if i not in rows]
        return vsub, leftover

    def solve(self, B: sp.Matrix, rhs: sp.Matrix) -> sp.Matrix:
        """B^{-1} rhs for a small square B of functions regular on M.

        LU pivots are accepted only where the entry does not reduce to zero on
        M (sympy's own pivot test could pick an entry that is a nonzero
        expression but vanishes on M); see :func:`nhham.lagrangian.algebra.solve_linear`.
        """
        iszero = (lambda e: self.reduce(e) == 0) if self.exact else None
        return solve_linear(B, rhs, iszero=iszero)

    def reduce(self, expr) -> sp.Expr:
        """``expr`` with solved variables substituted and rationally cancelled.

        Raises
        ------
        InputError
            Where ``expr`` is not defined on M (1/x on M = {x = 0}: W or a constraint's
            one-form singular on the constraint set).
        """
        red = self.reduction
        expr = sp.sympify(expr)
        return defined_where(expr, cancel(expr.xreplace(red.substitution)), red.substitution)

    # ------------------------------------------------------------ decisions
    @cached_property
    def policy(self) -> Policy:
        """The settings of this manifold's decisions as a :class:`Policy`."""
        return Policy(precision=self.precision, samples=self.samples, seed=self.seed,
                      exact=self.exact)

    def vanishes(self, expr, tol: float | None = None) -> Decision:
        """Decide whether ``expr`` vanishes identically on M.

        Parameters
        ----------
        expr : sympy.Expr
            A function of (q, v) and parameters.
        tol : float, optional
            Relative tolerance of the sampled test; default 1e-9 for float64
            and 10**(3 - digits) for mpmath.

        Returns
        -------
        Decision
            ``value`` True when it vanishes. Exact when the reduction decides
            (either way, see the module docstring); otherwise sampled
            (:func:`~nhham.lagrangian.engine.decide` with :class:`Vanishing`).
        """
        return decide(Vanishing(expr, tol), self, self.policy)

    @cached_property
    def curved(self) -> bool:
        """True when M has no rational parametrisation but points over F_p from a chart
        (:mod:`nhham.lagrangian.curved`): a holonomic constraint no coordinate enters
        linearly."""
        from nhham.lagrangian.domains import NotExact
        from nhham.lagrangian.points import exact_sampler

        try:
            exact_sampler(self, self.seed)
            return False
        except NotExact:
            pass
        try:
            return exact_sampler(self, self.seed, modular=True).chart is not None
        except NotExact:
            return False

    def has_real_point(self, constraints, policy: Policy) -> bool:
        """Whether {g = 0} in Q has a real point (:func:`has_real_point`), for the
        points over F_p of a chart of this M (the engine asks)."""
        return has_real_point(self.system, constraints, policy)

    def rank(self, matrix: sp.Matrix, tol: float | None = None) -> Decision:
        """Decide the rank of a matrix of functions on M (generic rank).

        Exact when every entry reduces to a number, when every entry
        vanishes, when a maximal minor is a nonzero function on M, or when a
        certificate is found (an r x r minor that is a nonzero function on M
        whose Schur complement vanishes on M); otherwise the rank at seeded
        sample points from singular values, with warnings where it is not the
        same at every point or a singular value is neither clearly zero nor
        clearly nonzero at this precision (:func:`~nhham.lagrangian.engine.decide`
        with :class:`Rank`).
        """
        return decide(Rank(matrix, tol), self, self.policy)

    def regular_block(self, matrix: sp.Matrix, rank: int):
        """Rows and columns of a best-conditioned regular rank x rank block.

        Parameters
        ----------
        matrix : sympy.Matrix, shape (R, K)
            A matrix of functions on M whose generic rank on M is ``rank``.
        rank : int

        Returns
        -------
        rows, cols : list of int
            The block ``matrix[rows, cols]``, chosen to maximise the worst
            ratio sigma_min(block) / ||matrix|| over the sample points of M
            (or over the one numeric value when the reduced matrix is
            constant): well conditioned and not small. A constant block
            scores double, because it puts no function of the state in a
            denominator. Ties go to the first block in lexicographic order.
        evidence : Decision
            ``value`` is ``(rows, cols)``; exact when the choice needed no
            sample points (a square regular matrix, or constant entries).
        """
        matrix = sp.Matrix(matrix)
        if rank == 0:
            return [], [], Decision(([], []), "exact", "empty block (rank 0)")
        if rank == matrix.rows == matrix.cols:
            rows = list(range(rank))
            return rows, list(rows), Decision((rows, list(rows)), "exact",
                                              "the whole (square, regular) matrix")
        reduced = matrix.applyfunc(self.reduce if self.exact else cancel)
        points: list = []
        if not reduced.free_symbols:
            samples = [np.array(reduced.evalf(), dtype=float)]
        else:  # the points where it is finite and real (log(x) at x > 0)
            points, values = self.finite_values([reduced])
            samples = [np.array(value, dtype=float) for (value,) in values]
        rows, cols, score = best_block(samples, rank)
        if rows is None:
            raise ComputationError(
                f"no regular {rank}x{rank} block found in a matrix of rank {rank} on M")
        detail = (f"block rows {rows}, columns {cols}: worst sigma_min(block)/||matrix|| "
                  f"{score:.3g} over {len(samples)} evaluation(s)")
        if points:
            return rows, cols, Decision((rows, cols), "sampled", detail,
                                        precision=self.precision_label, samples=len(points),
                                        points=record(points, self.variables))
        return rows, cols, Decision((rows, cols), "exact", detail + " (constant entries)")

    def exact_zero_test(self, expr):
        """Exact zero test of a reduced expression on M: (True | False | None, warning).

        True: zero on M (rational cancellation, or a Groebner remainder 0 modulo
        sin^2 + cos^2 = 1 and the residual equations of :attr:`reduction`); False: a
        nonzero function on M (only when the reduction parametrises M completely);
        None: undecided. The warning names a nonzero expression that vanishes at the
        given parameter values.
        """
        return zero_test(expr, self.reduction.residual, self.system.parameters,
                          self.system.parameter_values)

    def sampled_ranks(self, matrices, tol: float | None = None) -> list:
        """The ranks of several matrices at the same sample points (as :meth:`rank` with
        ``exact=False``), their distinct entries lambdified once: matrices that share
        entries (a matrix and the matrix bordered by a column) print each entry once.

        Whatever the units: singular values are compared with the largest one after the
        matrix is equilibrated by rows and columns (a change of units leaves the rank
        unchanged). Where that answer differs from the plain one (singular values over
        max(s_1, 1)), an entry could be rounding noise that equilibration blew up (a
        function vanishing on M, seen off M by the Newton projection): entries below the
        zero level of their size (:func:`value_scale`) are then set to 0 first.

        Parameters
        ----------
        matrices : sequence of sympy.Matrix
        tol : float, optional

        Returns
        -------
        list of Decision
        """
        matrices = [sp.Matrix(M) for M in matrices]
        if all(0 in M.shape for M in matrices):
            return [Decision(0, "exact", "empty matrix") for _ in matrices]
        points, resid = self.points()
        entries = list(dict.fromkeys(e for M in matrices for e in M))
        where = {e: i for i, e in enumerate(entries)}
        tol = self._tol(tol)
        zero = self._zero_level(resid)
        out = []
        with self._arithmetic():
            flat = self._entries_at(entries, points)
            sizes: list = []  # the entries' sizes, formed once if any matrix needs them

            def sizes_at():
                if not sizes:
                    sizes.append(self._entries_at(
                        [value_scale(e, self.variables) for e in entries], points))
                return sizes[0]

            for M in matrices:
                if 0 in M.shape:
                    out.append(Decision(0, "exact", "empty matrix"))
                    continue
                index = np.array([where[e] for e in M], dtype=np.intp).reshape(M.shape)
                values = [v[index] for v in flat]
                keep = [i for i, S in enumerate(values) if is_finite(S)]
                if not keep:
                    raise nowhere_finite(M, values[0], len(points))
                out.append(rank_from_values(
                    [values[i] for i in keep], [points[i] for i in keep], self.variables,
                    resid, tol, zero, self.precision,
                    lambda index=index, keep=keep: [sizes_at()[i][index] for i in keep],
                    skipped=len(points) - len(keep)))
        return out

    def _entries_at(self, entries, points) -> list:
        """The values of expressions at each point, one object array each (one lambdified
        function for all)."""
        f = self._lambdify([sp.Matrix(len(entries), 1, entries)])
        return [self._matrix_at(f, pt, (len(entries),)) for pt in points]

    def _arithmetic(self):
        """The working precision of the sampled arithmetic (mpmath's dps, or float64)."""
        return mpmath.workdps(self.precision) if self.precision else contextlib.nullcontext()

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
        # in TQ, where L is real (sqrt(1 - v^2) on part of it only: more starts)
        inside = (real_domain(self.system.lagrangian, self.variables + self.system.parameters)
                  if self.fibre == tuple(self.system.velocities) else None)
        for raw in self._raw_points(self.samples * (4 if inside is None else 40)):
            if len(pts) == self.samples:
                break
            attempts += 1
            try:
                pt, res = self._project(raw, eqs)
            except (ZeroDivisionError, ValueError, OverflowError, ArithmeticError,
                    np.linalg.LinAlgError):
                continue
            if res is None or (inside is not None and not inside(pt)):
                continue
            pts.append(pt)
            worst = max(worst, res)
        if not pts:
            raise EmptySubmanifoldError(
                f"could not find points on the submanifold defined by {list(self.equations)} "
                f"(Newton projection failed from {attempts} seeded starts; it may be empty: "
                f"equations without a real solution?)"
            )
        return pts, worst

    def _raw_points(self, count):
        rng = np.random.default_rng(self.seed)
        syms = self.variables
        out = []
        for _ in range(count):
            pt = {s: float(rng.uniform(*STATE_BOX)) for s in syms}
            for p in self.system.parameters:
                pt[p] = self.system.parameter_values.get(p, float(rng.uniform(*PARAMETER_BOX)))
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
            # a start where an equation is not finite is dropped (below): numpy's warnings
            # there would reach the user as the command's
            with np.errstate(all="ignore"):
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
            self._residual_cache[eqs] = (numeric_function(args, Fm, self.precision),
                                         numeric_function(args, Jm, self.precision))
        return self._residual_cache[eqs]

    def evaluator(self, matrix: sp.Matrix):
        """A function of a point of M (as from :meth:`points`) giving ``matrix`` there.

        The one route from expressions to numbers on the exact layers: compiled once
        (numpy in float64, mpmath at the manifold's precision); the result is a float
        array (float64: NaN where an entry is not a real number, sqrt(x) at x < 0) or an
        object array of mpf, of the matrix's shape.
        """
        matrix = sp.Matrix(matrix)
        f = self._lambdify([matrix])
        shape = matrix.shape

        def at(point):
            value = self._matrix_at(f, point, shape)
            if self.precision is not None:
                return value
            value = value.astype(complex)
            return np.where(value.imag == 0, value.real, np.nan)
        return at

    def finite_values(self, matrices: Sequence[sp.Matrix]) -> tuple[list, list]:
        """The sample points of M where every matrix is finite (and real), and the
        matrices' values there (:meth:`evaluator`): ``(points, [[value of each matrix]
        at each point])``.

        Raises
        ------
        InputError
            No point has them all finite: the entry that is not is named.
        """
        points, _ = self.points()
        fs = [self.evaluator(M) for M in matrices]
        values = [[f(pt) for f in fs] for pt in points]
        keep = [i for i, vals in enumerate(values) if all(is_finite(v) for v in vals)]
        if not keep:
            bad = next(j for j, v in enumerate(values[0]) if not is_finite(v))
            raise nowhere_finite(sp.Matrix(matrices[bad]), values[0][bad], len(points))
        return [points[i] for i in keep], [values[i] for i in keep]

    def _lambdify(self, exprs):
        return numeric_function(self.variables + self.system.parameters, exprs, self.precision)

    def _evaluate(self, f, pt):
        args = [pt[s] for s in self.variables
                + self.system.parameters]
        if self.precision is None:
            with np.errstate(all="ignore"):
                return f(*args)
        with mpmath.workdps(self.precision):
            return f(*args)

    def _matrix_at(self, f, pt, shape):
        """A lambdified matrix evaluated at a point, as an object array of ``shape``."""
        value = self._evaluate(f, pt)[0]
        if isinstance(value, mpmath.matrix):
            return np.array([[value[i, j] for j in range(value.cols)]
                             for i in range(value.rows)], dtype=object).reshape(shape)
        return np.array(value, dtype=object).reshape(shape)

    def _numeric_matrix(self, M, pt):
        return np.array(M.xreplace(pt).evalf(), dtype=complex).real.astype(float)

    def _zero_level(self, residual=0.0):
        """Below this relative size a sampled value is clearly zero."""
        base = Precision(self.precision).zero_level
        return max(base, 100.0 * float(residual or 0.0))

    def _tol(self, tol):
        if tol is not None:
            return tol
        return Precision(self.precision).tolerance

    def sampled_vanishes(self, expr, tol: float | None = None) -> Decision:
        """Whether ``expr`` vanishes at the seeded sample points of M (as
        :meth:`vanishes` with ``exact=False``), relative to the size of its terms.

        Parameters
        ----------
        expr : sympy.Expr
        tol : float, optional
            Relative tolerance (default: the precision's, see :meth:`vanishes`).

        Returns
        -------
        Decision
            Sampled, with the largest values, the points and warnings where the
            answer is doubtful at this precision.
        """
        points, resid = self.points()
        tol = self._tol(tol)
        f = self._lambdify([expr])
        scale_f = self._lambdify([value_scale(expr, self.variables)])
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
            # relative to the size of the terms, not to 1: unit-free
            scale = float(abs(scale))
            worst_rel = max(worst_rel, a / scale if scale else (0.0 if a == 0 else math.inf))
        vanishes = worst_rel <= tol
        warnings: tuple[str, ...] = ()
        zero = self._zero_level(resid)
        if not vanishes and worst_rel <= 1e3 * tol:
            warnings = (f"largest relative value {worst_rel:.3g} is within 1e3 of the "
                        f"tolerance {tol:g}: the answer is doubtful at this precision",)
        elif vanishes and worst_rel > zero:
            warnings = (f"largest relative value {worst_rel:.3g} is below the tolerance {tol:g} "
                        f"but above the zero level {zero:.3g}: it may not vanish (try more "
                        f"digits)",)
        return Decision(
            vanishes, "sampled",
            f"largest |value| {worst:.3g} (relative {worst_rel:.3g}) at {len(points)} seeded "
            f"points, tolerance {tol:g}",
            precision=self.precision_label, samples=len(points), max_abs=worst,
            point_residual=resid, warnings=warnings, points=record(points, self.variables),
        )





def has_real_point(system, constraints, policy: Policy) -> bool:
    """Whether {g = 0} (the curved constraints of a chart: in Q, or in TQ with Chetaev's)
    has a real point, found by Newton projection from seeded starts. Points over F_p lie
    over the algebraic closure of Q and say nothing of that (x^2 + y^2 + 1 = 0 has them).
    The constraints a chart leaves out are linear in a coordinate with a constant
    coefficient: they have a real solution at every real point of these. Memoised."""
    return _has_real_point(system, tuple(constraints), policy.precision, policy.seed)


@functools.lru_cache(maxsize=32)
def _has_real_point(system, constraints, precision, seed) -> bool:
    in_tq = any(sp.sympify(g).free_symbols & set(system.velocities) for g in constraints)
    try:  # a chart with Chetaev's constraints lives in TQ: look there
        Submanifold(system, constraints, precision=precision, samples=1, seed=seed,
                    fibre=system.velocities if in_tq else ()).points()
    except ComputationError:
        return False
    return True
