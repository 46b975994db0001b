"""Frobenius integrability of the constraint distribution (is it secretly holonomic?).

The constraints φ_i = μ_iA(q) v^A + h_i(q) confine the velocities at q to the affine
space {v : μ(q) v = −h(q)}, a translate of the linear space D_q = ker μ(q). The
*distribution* D = ker μ ⊂ TQ is what Frobenius' theorem is about:

- D is integrable (involutive) iff for every pair of fields X, Y in D the bracket
  [X, Y] is in D, iff dμ_i ∧ μ_1 ∧ ... ∧ μ_m = 0 for every i. Since
  μ_i([X, Y]) = −dμ_i(X, Y) for X, Y in ker μ, it is tested as
  dμ_i(X_a, X_b) = 0 on a basis X_1..X_{n−m} of D (all i, a < b).
- Every row of μ is used, complete lifts of holonomic constraints included: their
  one-forms dg are closed and add nothing to the obstruction, and the test runs on
  Q_1 = {g = 0} (exact reduction, else seeded samples of Q_1), because only there
  does the motion take place.
- Integrable linear constraints (h = 0) are holonomic in disguise: locally
  D = ker(dF_1, ..., dF_m) and the motion keeps F constant (the leaf is fixed by the
  initial data). With h ≠ 0 the answer concerns the linear part only: the motion
  then satisfies d/dt F = (a function of q fixed by h), i.e. it crosses the leaves
  of D at a prescribed rate (for ẋ = 1: x = t + c, a rheonomic holonomic
  constraint), and "integrable" means exactly that, not that the affine
  constraint set is the tangent bundle of a submanifold.

``integrable`` is True / False when every decision was clear, and None when a
sampled decision was doubtful at the chosen precision (see :mod:`nhham.lagrangian.submanifold`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import sympy as sp

from nhham.errors import BudgetExceeded, ComputationError
from nhham.lagrangian.algebra import cancel
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.domains import Degree, ModP, NotExact, evaluate
from nhham.lagrangian.formulas import frobenius_terms
from nhham.lagrangian.linalg import ListMatrix, degree_solve, exact_rank, field_solve
from nhham.lagrangian.engine import Policy, decide, policy_of, proof_at_a_point
from nhham.lagrangian.points import jacobian_row
from nhham.lagrangian.submanifold import Submanifold
from nhham.settings import SEED, Precision
from nhham.system.expressions import short

__all__ = ["Integrability", "Frobenius", "integrability", "frobenius", "frobenius_sampled",
           "not_applicable"]


@dataclass(frozen=True)
class Integrability:
    """Frobenius test of D = ker μ on Q_1.

    Attributes
    ----------
    integrable : bool or None
        True when D is involutive, False when it is not, None when undecidable at
        the chosen precision.
    rank : int
        Rank n − m of D.
    basis : sympy.Matrix or None, shape (n, n − m)
        Columns X_a spanning D (solved for the m best-conditioned dependent
        components; denominators may vanish on a thin set). None when the test
        ran at exact points (the basis is then never written out, and an
        obstruction is its value at the rational point that proved it, None for a
        point over F_p).
    obstructions : tuple of (str, int, int, sympy.Expr or None)
        ``(constraint label, a, b, dμ_i(X_a, X_b))`` for every term found not to
        vanish on Q_1.
    decisions : tuple of (str, Decision)
        Every vanishing decision with its evidence.
    method : str
        ``"exact"`` when every decision was exact, ``"sampled"`` otherwise, and
        ``"not applicable"`` for nonlinear (Chetaev) constraints (:func:`not_applicable`).
    warnings : tuple of str
    mu : sympy.Matrix, shape (m, n)
    coordinates : tuple of sympy.Symbol
    labels : tuple of str
    """

    integrable: bool | None
    rank: int
    basis: sp.Matrix | None
    obstructions: tuple
    decisions: tuple
    method: str
    warnings: tuple
    mu: sp.Matrix
    coordinates: tuple
    labels: tuple

    def __bool__(self):
        return bool(self.integrable)

    @property
    def generic(self) -> bool | None:
        """The verdict for generic parameter values.

        False also where an exact decision found a term that is a nonzero function but
        vanishes at the given parameter values (``integrable`` is then None: the answer
        at those values is decided by substituting them, :mod:`nhham.verdict.values`).
        """
        if self.integrable is None and any(
                d.method == "exact" and d.value is False for _, d in self.decisions):
            return False
        return self.integrable

    @cached_property
    def first_integrals(self) -> tuple:
        """``(label, F)`` with dF = μ_i for every closed row μ_i (F None otherwise).

        Best effort (sympy's ``integrate``); a row that is integrable only after
        combination with others, or with an integrating factor, gets None.
        """
        out = []
        for i, lab in enumerate(self.labels):
            out.append((lab, _potential(self.mu.row(i), self.coordinates)))
        return tuple(out)

    def describe(self) -> str:
        """One line: the verdict and how it was reached."""
        if self.method == "not applicable":
            return ("not applicable (nonlinear constraints: ker d phi/d v depends on v, no "
                    "distribution on Q)")
        if self.integrable is None:
            verdict = "undecided"
        else:
            verdict = "integrable (holonomic in disguise)" if self.integrable else \
                "not integrable (truly nonholonomic)"
        text = f"{verdict} ({self.method}; D of rank {self.rank})"
        if self.obstructions:
            lab, a, b, expr = self.obstructions[0]
            where = "" if self.basis is not None else " at an exact point of Q_1"
            value = "!= 0 modulo p" if expr is None else f"= {short(expr)}"
            text += f"; e.g. d{lab}(X_{a + 1}, X_{b + 1}) {value}{where}"
        if self.warnings:
            text += " WARNING: " + "; ".join(self.warnings)
        return text


def integrability(system, *, precision: int | None = None, samples: int = 6,
                  seed: int = SEED, exact: bool = True,
                  policy: Policy | None = None) -> Integrability:
    """Frobenius test of the distribution annihilated by all the μ rows of ``system``.

    Decided by :func:`~nhham.lagrangian.engine.decide` on Q_1 = {g = 0}: symbolically
    up to ``policy.closed_form_size`` coordinates, else at exact points of Q_1, else at
    sampled points (:class:`Frobenius`).

    Parameters
    ----------
    system : nhham.System
    precision, samples, seed, exact
        As in :func:`nhham.lagrangian.analysis.analyze_constraints`.
    policy : Policy, optional
        All the settings in one object, instead of the four above.

    Returns
    -------
    Integrability

    Examples
    --------
    The rolling disk's constraints dx - R cos(theta) dphi, dy - R sin(theta) dphi: by hand,
    d mu_1(X_1, X_2) = R sin(theta) and d mu_2(X_1, X_2) = -R cos(theta) on the kernel
    basis X_1 = d/dtheta, X_2 = R cos(theta) d/dx + R sin(theta) d/dy + d/dphi.

    >>> from nhham import integrability, models
    >>> result = integrability(models.rolling_disk(symbolic=True))
    >>> result.integrable, result.method
    (False, 'exact')
    >>> [str(term) for _, _, _, term in result.obstructions]
    ['R*sin(theta)', '-R*cos(theta)']
    """
    policy = policy_of(policy, "integrability", precision=precision, samples=samples,
                       seed=seed, exact=exact)
    if not system.is_affine:
        return not_applicable(system)
    question, Q1 = _question(system, policy)
    return decide(question, Q1, policy)


def integrability_proved_at_values(system, policy: Policy) -> Integrability | None:
    """Non-integrability proved at one point of Q_1 over F_p drawn with the parameters
    at their values (a nonzero term dmu_i(X_a, X_b)), else None.

    A reduction decides for generic parameters; this says whether the scene's own
    values are among the exceptions (:mod:`nhham.lagrangian.exceptional` asks it where
    Q_1 has no rational points)."""
    question, Q1 = _question(system, policy)
    return proof_at_a_point(question, Q1, policy)


def _question(system, policy) -> tuple["Frobenius", Submanifold]:
    """The Frobenius question and Q_1 = {g = 0} it is asked on."""
    labels = tuple(f"{lab}.lift" if i < len(system.holonomic) else lab
                   for i, lab in enumerate(system.constraint_labels))
    Q1 = Submanifold(system, system.holonomic, precision=policy.precision,
                     samples=policy.samples, seed=policy.seed, fibre=(), exact=policy.exact)
    return Frobenius(system, labels), Q1


class Frobenius:
    """The Frobenius test of ker μ on Q_1 as a question for
    :func:`~nhham.lagrangian.engine.decide` (the answer: :class:`Integrability`).

    Exact reduction: the kernel basis and the obstructions written out symbolically
    (:func:`frobenius`), up to ``policy.closed_form_size`` coordinates. At exact points:
    the kernel basis X_a (dependent components by Cramer's rule, the same dependent set
    at every point) and dμ_i(X_a, X_b) (:func:`nhham.lagrangian.formulas.frobenius_terms`)
    in exact arithmetic; one nonzero value proves non-integrability, values that vanish
    at k points give "integrable" with the Schwartz–Zippel bound (union over the terms).
    Sampled: :func:`frobenius_sampled`.
    """

    what = "dmu_i(X_a, X_b) on Q_1"
    residues = True  # decided at smooth points over F_p of a curved Q_1 too

    def __init__(self, system, labels):
        self.system, self.labels = system, tuple(labels)
        self.mu, self.q, self.common, self.trivial = _distribution(system, labels)
        self.rows = [list(self.mu.row(i)) for i in range(self.mu.rows)]
        self.dep = None
        self.found: tuple | None = None

    @cached_property
    def dmu(self) -> list:
        """dmu[i][A][B] = d_A mu_iB - d_B mu_iA, formed once Q_1 has exact points."""
        n = len(self.q)
        out = []
        for rows in one_form_differentials(self.mu, self.q):
            block = []
            for entries in rows:
                row = [sp.S.Zero] * n
                for B, e in entries:
                    row[B] = e
                block.append(row)
            out.append(block)
        return out

    def reduced(self, manifold, policy):
        if len(self.q) <= policy.closed_form_size:
            return frobenius(self.system.mu, self.q, manifold, self.labels)
        return self.trivial

    def value(self, env, degrees: bool = False):
        values, self.dep = _frobenius_terms(env, self.rows, self.dmu, self.dep,
                                            exact=not degrees)
        return values

    def proved_modulo_p(self, values):
        """Non-integrability proved by a term nonzero at a point over F_p (its value
        over Q at the same rational point, or on a curved Q_1 at a point of the
        component, is nonzero); None when every term vanishes there."""
        n, m, labels = len(self.q), self.mu.rows, self.labels
        for (i, a, b), w in values.items():
            if w != 0:
                dec = Decision(False, "exact", f"d{labels[i]}(X_{a + 1}, X_{b + 1}) != 0 at "
                               f"a random point of Q_1 modulo the prime 2^61 - 1 (proof)",
                               samples=1, error_bound=0.0)
                return Integrability(False, n - m, None, ((labels[i], a, b, None),),
                                     ((f"d{labels[i]}(X_{a + 1}, X_{b + 1})", dec),), "exact",
                                     (), **self.common)
        return None

    def observe(self, values) -> bool:
        for (i, a, b), w in values.items():
            if w != 0:
                self.found = (i, a, b, w)
                return True
        return False

    def pending_error(self, degrees, count, bound):
        worst = max((Degree.of(d).num for d in degrees.values()), default=0)
        return bound(worst, count, terms=len(degrees))

    def conclude(self, count, degrees, bound) -> Integrability:
        n, m, labels = len(self.q), self.mu.rows, self.labels
        if self.found is not None:
            i, a, b, w = self.found
            modular = isinstance(w, ModP)  # a residue has no size: its value is not kept
            dec = Decision(False, "exact", f"d{labels[i]}(X_{a + 1}, X_{b + 1}) = "
                           f"{'a nonzero residue mod p' if modular else w} at an exact "
                           f"point of Q_1 (proof)", samples=count, error_bound=0.0)
            return Integrability(False, n - m, None, ((labels[i], a, b, None if modular else
                                                       sp.Rational(int(w.numerator),
                                                                   int(w.denominator))),),
                ((f"d{labels[i]}(X_{a + 1}, X_{b + 1})", dec),), "exact", (), **self.common)
        worst = max((Degree.of(d).num for d in degrees.values()), default=0)
        error = self.pending_error(degrees, count, bound)
        dec = Decision(True, "exact at points",
                       f"all {len(degrees)} terms dmu_i(X_a, X_b) vanish at {count} random "
                       f"exact points of Q_1 (degree <= {worst})", samples=count,
                       error_bound=error)
        return Integrability(True, n - m, None, (), (("dmu_i(X_a, X_b) on Q_1", dec),),
                             "exact at points", (), **self.common)

    def sampled(self, manifold, policy):
        return self.trivial or frobenius_sampled(
            self.system, self.labels, precision=policy.precision, samples=policy.samples,
            seed=policy.seed)


def frobenius_sampled(system, labels, *, precision: int | None = None, samples: int = 6,
                      seed: int = SEED) -> Integrability:
    """Frobenius test of ker μ at seeded floating-point points of Q_1.

    At each point a kernel basis X_a of μ(q) (orthonormal, from the SVD) and
    dμ_i(X_a, X_b) are computed numerically; a term is nonzero when it exceeds
    the tolerance relative to |dμ_i| (so "not integrable" is read off one clear
    value), zero when every term is below the zero level at every point, and the
    verdict is None (undecided) in between. Used where Q_1 has no exact points
    and the system is too large for a symbolic kernel basis.
    """
    mu, q, common, trivial = _distribution(system, labels)
    if trivial is not None:
        return trivial
    m, n = mu.rows, len(q)
    Q1 = Submanifold(system, system.holonomic, precision=precision, samples=samples,
                     seed=seed, fibre=(), exact=False)
    _, residual = Q1.points()
    grads = [[jacobian_row(mu[i, A], q) for A in range(n)] for i in range(m)]
    dmu = sp.Matrix([[grads[i][A][B] - grads[i][B][A] for A in range(n) for B in range(n)]
                     for i in range(m)])
    points, values = Q1.finite_values([mu, dmu])
    prec = Precision(precision)
    worst, doubtful, found = 0.0, False, None
    for mu_at, dmu_at in values:
        M = np.array(mu_at, dtype=float)
        D = np.array(dmu_at, dtype=float).reshape(m, n, n)
        X = np.linalg.svd(M)[2][m:].T          # orthonormal basis of ker mu(q)
        for i in range(m):
            T = X.T @ D[i] @ X                  # T[a, b] = dmu_i(X_a, X_b) (up to sign)
            scale = max(1.0, float(np.abs(D[i]).max()))
            value = float(np.abs(T).max()) / scale
            worst = max(worst, value)
            if value > 1e3 * prec.tolerance and found is None:
                a, b = np.unravel_index(np.argmax(np.abs(T)), T.shape)
                found = (i, int(min(a, b)), int(max(a, b)), float(T[a, b]))
            elif value > prec.zero_level:
                doubtful = True
    how = (f"{len(points)} seeded points of Q_1 ({prec.label}); largest |dmu_i(X_a, X_b)| / "
           f"|dmu_i| = {worst:.3g}")
    if found is not None:
        i, lo, hi, value = found
        dec = Decision(False, "sampled", "a term is clearly nonzero at " + how,
                       precision=prec.label, samples=len(points), max_abs=worst,
                       point_residual=residual)
        return Integrability(False, n - m, None, ((labels[i], lo, hi, sp.Float(value, 6)),),
                             ((f"d{labels[i]}(X_{lo + 1}, X_{hi + 1})", dec),), "sampled", (),
                             **common)
    warn = (f"terms neither clearly zero nor clearly nonzero at {prec.label}",) \
        if doubtful else ()
    dec = Decision(True if not doubtful else False, "sampled", "every term vanishes at " + how,
                   precision=prec.label, samples=len(points), max_abs=worst,
                   point_residual=residual, warnings=warn)
    return Integrability(None if doubtful else True, n - m, None, (),
                         (("dmu_i(X_a, X_b) on Q_1", dec),), "sampled", warn, **common)


def not_applicable(system) -> Integrability:
    """The answer for a system with nonlinear (Chetaev) constraints: ker dφ/dv depends on
    the velocities, so it is no distribution on Q and Frobenius' theorem does not apply
    (``integrable`` None, ``method`` "not applicable"; ``DESIGN.md`` §2).

    Examples
    --------
    >>> from nhham import System
    >>> s = System(["x", "y"], "(x_dot**2 + y_dot**2)/2", ["x_dot**2 + y_dot**2 - 1"])
    >>> answer = not_applicable(s)
    >>> answer.integrable, answer.method
    (None, 'not applicable')
    >>> answer.describe()
    'not applicable (nonlinear constraints: ker d phi/d v depends on v, no distribution on Q)'
    """
    labels = system.m1_labels[len(system.holonomic):]
    return Integrability(None, system.n - system.m, None, (), (), "not applicable", (),
                         mu=sp.Matrix(system.mu), coordinates=tuple(system.coordinates),
                         labels=tuple(labels))


@functools.lru_cache(maxsize=8)
def _differentials(mu: sp.ImmutableMatrix, q: tuple) -> tuple:
    m, n = mu.shape
    zero = sp.S.Zero
    out = []
    for i in range(m):
        grads = [jacobian_row(mu[i, A], q) for A in range(n)]  # [B][A]: d mu_iB / d q^A
        # most pairs are two zeros (jacobian_row's S.Zero): no subtraction for them
        out.append(tuple(tuple((B, e) for B in range(n)
                               if (grads[B][A] is not zero or grads[A][B] is not zero)
                               and (e := grads[B][A] - grads[A][B]) != 0)
                         for A in range(n)))
    return tuple(out)


def one_form_differentials(mu, coordinates) -> tuple:
    """d mu_i by its entries that are not identically zero: per i, per A, the pairs
    (B, d_A mu_iB - d_B mu_iA) (the sign of
    :func:`~nhham.lagrangian.formulas.frobenius_terms`). Memoised: the Frobenius test
    and the check of the parameter values read the same ones (most entries are zero: a
    snake's mu_i involves its first i links only).

    Examples
    --------
    >>> import sympy as sp
    >>> x, y, z = sp.symbols("x y z")
    >>> one_form_differentials(sp.Matrix([[1, 0, -y]]), (x, y, z))  # dx - y dz
    (((), ((2, -1),), ((1, 1),)),)
    """
    return _differentials(sp.ImmutableMatrix(mu), tuple(coordinates))


def _distribution(system, labels):
    """(mu, q, the fields every result shares, the result where the test is trivial):
    no constraint, or a distribution of rank at most 1 (always integrable)."""
    mu, q = sp.Matrix(system.mu), tuple(system.coordinates)
    common = dict(mu=mu, coordinates=q, labels=tuple(labels))
    trivial = None
    if mu.rows == 0 or len(q) - mu.rows <= 1:
        trivial = frobenius(mu, q, Submanifold(system, (), fibre=()), labels)
    return mu, q, common, trivial


def _frobenius_terms(env, rows, dmu, dep, exact=True):
    """{(i, a, b): dμ_i(X_a, X_b)} at one point (exact values, or Degree bounds with
    ``exact=False``), and the pivot columns of μ used for the kernel basis."""
    cache: dict = {}
    M = ListMatrix([evaluate(r, env, cache) for r in rows])
    D = [[evaluate(r, env, cache) for r in dmu_i] for dmu_i in dmu]
    if dep is None:
        rank, _, dep = exact_rank(M.rows)
        if rank < M.shape[0]:
            raise NotExact("mu is rank deficient at a random point")
    return frobenius_terms(M, D, dep, solve=field_solve if exact else degree_solve), dep


def frobenius(mu, coordinates, manifold: Submanifold, labels=None) -> Integrability:
    """Frobenius test of ker μ for one-forms μ (rows, shape (m, n)) on a Submanifold of Q.

    Parameters
    ----------
    mu : sympy.Matrix, shape (m, n)
        Coefficients μ_iA(q) of m independent one-forms.
    coordinates : sequence of sympy.Symbol
        q^1..q^n.
    manifold : Submanifold
        Where the decisions are made (Q itself, or Q_1), with ``fibre=()``.
    labels : sequence of str, optional
        Names of the rows (default ``mu[i]``).
    """
    mu = sp.Matrix(mu)
    q = tuple(coordinates)
    m, n = mu.rows, len(q)
    labels = tuple(labels) if labels is not None else tuple(f"mu[{i}]" for i in range(m))
    common = dict(mu=mu, coordinates=q, labels=labels)
    if m == 0:
        return Integrability(True, n, sp.eye(n), (), (), "exact", (), **common)
    if n - m <= 1:
        return Integrability(True, n - m, None, (), (("rank of D", Decision(
            True, "exact", f"D has rank {n - m} <= 1: always integrable")),), "exact", (),
            **common)
    basis = _kernel_basis(mu, manifold)
    K = [sp.Matrix(n, n, lambda B, A: sp.diff(mu[i, A], q[B])) for i in range(m)]
    decisions, obstructions, doubtful = [], [], False
    for i in range(m):
        for a in range(n - m):
            for b in range(a + 1, n - m):
                X, Y = basis[:, a], basis[:, b]
                w = cancel((X.T * K[i] * Y)[0] - (Y.T * K[i] * X)[0])
                dec = manifold.vanishes(w)
                decisions.append((f"d{labels[i]}(X_{a + 1}, X_{b + 1})", dec))
                doubtful |= bool(dec.warnings)
                if not dec.value:
                    obstructions.append((labels[i], a, b, manifold.reduce(w)
                                         if manifold.exact else w))
    if obstructions:
        bad = [d for _, d in decisions if not d.value]
        integrable = False if any(not d.warnings for d in bad) else None
    else:
        integrable = None if doubtful else True
    method = "exact" if all(d.method == "exact" for _, d in decisions) else "sampled"
    warnings = tuple(f"{s}: {w}" for s, d in decisions for w in d.warnings)
    return Integrability(integrable, n - m, basis, tuple(obstructions), tuple(decisions),
                         method, warnings, **common)


def _kernel_basis(mu, manifold):
    """Columns X_a spanning ker μ: free components e_a, dependent ones solved."""
    m, n = mu.shape
    try:
        _, dep, _ = manifold.regular_block(mu, m)
    except ComputationError:
        dep = list(range(m))
    free = [j for j in range(n) if j not in dep]
    sol = manifold.solve(mu.extract(list(range(m)), dep),
                    -mu.extract(list(range(m)), free))
    basis = sp.zeros(n, len(free))
    for a, j in enumerate(free):
        basis[j, a] = 1
        for t, d in enumerate(dep):
            basis[d, a] = sol[t, a]
    return basis


def _potential(row, q):
    """F with dF = row (one-form coefficients), or None when the form is not closed."""
    n = len(q)
    for A in range(n):
        for B in range(A + 1, n):
            if cancel(sp.diff(row[A], q[B]) - sp.diff(row[B], q[A])) != 0:
                return None
    F = sp.S.Zero
    try:
        for A in range(n):
            rest = cancel(row[A] - sp.diff(F, q[A]))
            if rest != 0:
                F += sp.integrate(rest, q[A])
        if any(cancel(sp.diff(F, q[A]) - row[A]) != 0 for A in range(n)):
            return None
    except BudgetExceeded:  # an expiry is not a failed integration
        raise
    except Exception:  # pragma: no cover - sympy integration failure
        return None
    return sp.simplify(F) if sp.count_ops(F) < 40 else F
