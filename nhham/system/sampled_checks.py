"""The checks of a :class:`~nhham.system.System` under construction that need numbers.

Two properties of the input are decided at seeded random points of the state and of
the parameters (reproducible run to run): the constraint one-forms are independent
(:func:`check_dependence`: a dependent row is refused, or dropped and recorded as a
:class:`DroppedConstraint` with ``drop_redundant``), and the Lagrangian is regular
(:func:`singular_rank`: W = d2L/dv dv invertible or not). A float64 rank deficiency
is confirmed in high precision before it is reported (units such as m = 1e-16).
The values at the points come from one fast pass over the expression trees
(:func:`numeric_samples`), with sympy's ``evalf`` as the fallback.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping

import numpy as np
import sympy as sp

from nhham.errors import (
    BudgetExceeded,
    RedundantConstraintError,
    ValidationError,
)
from nhham.settings import PARAMETER_BOX, STATE_BOX
from nhham.system.rank import float_rank, precise_ranks
from nhham.system.velocities import one_forms

__all__ = ["DroppedConstraint", "check_dependence", "singular_rank", "singular_message",
           "numeric_samples", "numeric", "sample_q", "finite_samples", "evaluate_at",
           "NoFastEvaluation",
           "VALIDATION_SEED", "VALIDATION_SAMPLES"]

# Random points used for generic-rank decisions are drawn from this seed so
# that validation is reproducible run to run.
VALIDATION_SEED = 20261121
VALIDATION_SAMPLES = 4


@dataclass(frozen=True)
class DroppedConstraint:
    """A constraint removed because its one-form is a combination of others.

    Attributes
    ----------
    label : str
        Key path of the dropped constraint (``constraints[2]``).
    expression : sympy.Expr
        The dropped phi.
    combination : dict
        ``{label: coefficient}`` with phi_dropped = sum coefficient * phi_label
        (coefficients are functions of q).

    Examples
    --------
    The second constraint is x times the first:

    >>> from nhham import System
    >>> s = System(["x", "y"], "(x_dot**2 + y_dot**2)/2",
    ...            constraints=["y_dot - x*x_dot", "x*y_dot - x**2*x_dot"], drop_redundant=True)
    >>> s.m, s.phi
    (1, (-x*x_dot + y_dot,))
    >>> dropped, = s.dropped
    >>> dropped.label, dropped.expression, dict(dropped.combination)
    ('constraints[1]', -x**2*x_dot + x*y_dot, {'constraints[0]': x})
    """

    label: str
    expression: sp.Expr
    combination: Mapping[str, sp.Expr]


# ----------------------------------------------------- numeric sample values
class NoFastEvaluation(Exception):
    """The fast evaluator met something it does not handle; use sympy's evalf."""


_NUMPY_FUNCTIONS = {
    sp.sin: np.sin, sp.cos: np.cos, sp.tan: np.tan, sp.exp: np.exp, sp.log: np.log,
    sp.sinh: np.sinh, sp.cosh: np.cosh, sp.tanh: np.tanh,
    sp.asin: np.arcsin, sp.acos: np.arccos, sp.atan: np.arctan,
    sp.cot: lambda z: 1 / np.tan(z), sp.sec: lambda z: 1 / np.cos(z),
    sp.csc: lambda z: 1 / np.sin(z),
}


def evaluate_at(exprs, points):
    """Values of ``exprs`` at all ``points`` at once, shape (len(exprs), len(points)).

    Complex float64 arithmetic over one walk of the expression trees (shared
    subexpressions evaluated once). Raises :class:`NoFastEvaluation` for any
    node it does not know and for non-finite values, so that the caller falls
    back to ``xreplace(...).evalf()`` and keeps its exact behaviour there.
    """
    symbols = set().union(*(p.keys() for p in points)) if points else set()
    env = {s: np.array([complex(p[s]) for p in points]) for s in symbols}
    memo: dict = {}

    def ev(e):
        hit = memo.get(e)
        if hit is not None:
            return hit
        if e.is_Symbol:
            if e not in env:
                raise NoFastEvaluation
            val = env[e]
        elif e.is_Atom:
            if not e.is_number:
                raise NoFastEvaluation
            try:
                val = np.complex128(complex(e))
            except (TypeError, ValueError, OverflowError):
                raise NoFastEvaluation from None
        elif e.is_Add:
            val = ev(e.args[0])
            for a in e.args[1:]:
                val = val + ev(a)
        elif e.is_Mul:
            val = ev(e.args[0])
            for a in e.args[1:]:
                val = val * ev(a)
        elif e.is_Pow:
            base, exp = ev(e.base), e.exp
            if exp.is_Integer and abs(int(exp)) <= 64:
                k = int(exp)
                val = base ** k if k >= 0 else 1 / base ** (-k)
            else:
                val = base ** ev(exp)
        elif e.func in _NUMPY_FUNCTIONS and len(e.args) == 1:
            val = _NUMPY_FUNCTIONS[e.func](ev(e.args[0]))
        else:
            raise NoFastEvaluation
        memo[e] = val
        return val

    try:
        with np.errstate(all="ignore"):
            out = np.array([np.broadcast_to(ev(sp.sympify(e)), (len(points),)) for e in exprs],
                           dtype=complex).reshape(len(exprs), len(points))
    except (ArithmeticError, TypeError, ValueError):
        raise NoFastEvaluation from None
    if not np.all(np.isfinite(out)):
        raise NoFastEvaluation
    return out


def numeric_samples(matrix, points, label="lagrangian"):
    """``[numeric(matrix, p, label) for p in points]``, by one fast numeric pass.

    Falls back to :func:`numeric` (sympy evalf, with its error messages)
    whenever the fast pass cannot give finite values.
    """
    rows, cols = matrix.shape
    if rows * cols and points:
        try:
            values = evaluate_at(list(matrix), points)
        except NoFastEvaluation:
            pass
        else:
            values = _real(values)
            return [values[:, k].reshape(rows, cols) for k in range(len(points))]
    return [numeric(matrix, p, label) for p in points]


def _real(values):
    """Complex values as floats, NaN where one is not real (outside a function's domain:
    its real part would be a number the input never had)."""
    return np.where(values.imag == 0, values.real, np.nan)


def finite_samples(matrix, system, rng, labels):
    """Seeded points of the state and the matrix's values there (``numeric_samples``),
    only where every entry is finite: a point outside the domain of L or a constraint
    (log(x) at x < 0) says nothing about a generic rank. Up to four draws of
    :data:`VALIDATION_SAMPLES` points are made until that many are finite.

    Parameters
    ----------
    matrix : sympy.Matrix
    system : System
    rng : numpy.random.Generator
    labels : sequence of str
        The key path of each row (for the refusal).

    Returns
    -------
    (list of dict, list of ndarray)

    Raises
    ------
    ValidationError
        No point has every entry finite: the row of the first one that is not is named.
    """
    points, samples, first = [], [], None
    for _ in range(4):
        drawn = sample_q(system, rng, VALIDATION_SAMPLES)
        for pt, S in zip(drawn, numeric_samples(matrix, drawn, labels[0])):
            if np.all(np.isfinite(S)):
                points.append(pt)
                samples.append(S)
            elif first is None:
                first = S
        if len(points) >= VALIDATION_SAMPLES:
            break
    if not points:
        row = int(np.argwhere(~np.isfinite(first))[0][0])
        raise ValidationError([f"{labels[row]}: {sp.sstr(matrix[row, :].tolist()[0])} is not "
                               f"finite at any of {4 * VALIDATION_SAMPLES} random points of "
                               f"the state; L and the constraints must be defined on it"])
    return points[:VALIDATION_SAMPLES], samples[:VALIDATION_SAMPLES]


def sample_q(system, rng, count):
    """Random numeric substitutions for coordinates and parameters."""
    points = []
    for _ in range(count):
        sub = {q: rng.uniform(*STATE_BOX) for q in system.coordinates}
        sub.update({v: rng.uniform(*STATE_BOX) for v in system.velocities})
        for p in system.parameters:
            sub[p] = system.parameter_values.get(p, rng.uniform(*PARAMETER_BOX))
        points.append(sub)
    return points


def numeric(matrix, sub, label="lagrangian"):
    """Evaluate a symbolic matrix at a sample point; non-numeric results are input errors.
    An entry that is not a real number there (sqrt(x) at x < 0, atan2 of 1/0) is NaN."""
    try:
        value = matrix.xreplace(sub)
    except TypeError:  # sympy compares NaN (atan2(0, 1/0)): undefined at this point
        return np.full(matrix.shape, np.nan)
    except ValueError as exc:  # a Derivative (of Abs) wrt a velocity replaced by a number
        raise _not_smooth(label, exc) from None
    try:
        return _real(np.array(value.evalf(), dtype=complex))
    except (TypeError, ValueError) as exc:
        raise _not_smooth(label, exc) from None


def _not_smooth(label, exc) -> ValidationError:
    return ValidationError([
        f"{label}: cannot evaluate second derivatives at a sample point "
        f"({' '.join(str(exc).split())}); the "
        f"Lagrangian must be smooth in the velocities (no Abs, sign or other kinks)"])


def check_dependence(system, cons, hols, drop_redundant):
    """Find affine constraints whose mu row is a combination of earlier rows.

    The generic rank over functions of q is decided at seeded random points
    (a row is dependent when it is dependent at every sample); the exact
    combination is then solved symbolically to name it.

    Returns (kept constraints, dropped, mu of lifts + constraints or None
    when a row was dropped or there are none).
    """
    rows = list(system.complete_lifts) + list(cons)  # holonomic is set before this runs
    labels = [f"holonomic[{i}]" for i in range(len(hols))] + [
        f"constraints[{i}]" for i in range(len(cons))
    ]
    if not rows:
        return tuple(cons), (), None
    vels = system.velocities
    mu = one_forms(rows, vels)
    rng = np.random.default_rng(VALIDATION_SEED)
    points, samples = finite_samples(mu, system, rng, labels)
    independent: list[int] = []
    dependent: list[tuple[int, dict]] = []
    for i in range(len(rows)):
        trial = independent + [i]
        full = len(trial)
        # A float64 deficiency may come from the units: confirm it in high precision.
        if (max(float_rank(S[trial]) for S in samples) == full
                or precise_ranks(mu, points, [trial])[0] == full):
            independent.append(i)
            continue
        dependent.append((i, _combination(mu, rows, independent, i, vels)))
    if not dependent:
        return tuple(cons), (), mu
    problems, dropped = [], []
    points = sample_q(system, np.random.default_rng(VALIDATION_SEED + 2), VALIDATION_SAMPLES)
    for i, coeffs in dependent:
        combo = " + ".join(f"({c})*{labels[j]}" for j, c in coeffs.items()) or "0"
        # Redundant only if h is the same combination; otherwise phi_i minus
        # the combination is a function of q alone: a hidden position constraint.
        rest = sp.expand(rows[i] - sum((c * rows[j] for j, c in coeffs.items()), sp.S.Zero))
        position_part = rest.xreplace({v: 0 for v in vels})
        if not _vanishes_at(position_part, points):
            problems.append(
                f"{labels[i]}: its one-form is {combo} but the affine parts differ: together "
                f"they imply the position constraint {sp.trigsimp(position_part)} = 0; give "
                f"that as a holonomic constraint instead"
            )
        elif labels[i].startswith("holonomic"):  # drop_redundant drops velocity constraints
            problems.append(
                f"{labels[i]}: the complete lift {rows[i]} is a combination of the others: "
                f"{labels[i]} = {combo}; the constraint is redundant: remove it from holonomic"
            )
        elif not drop_redundant:
            problems.append(
                f"{labels[i]}: {rows[i]} is redundant, a combination of the others: "
                f"{labels[i]} = {combo} ({RedundantConstraintError.ADVICE})"
            )
        else:
            dropped.append(DroppedConstraint(labels[i], rows[i],
                                             MappingProxyType({labels[j]: c for j, c in coeffs.items()})))
    if problems:
        raise RedundantConstraintError(problems)
    gone = {d.label for d in dropped}
    kept = tuple(c for k, c in enumerate(cons) if f"constraints[{k}]" not in gone)
    return kept, tuple(dropped), None


def _combination(mu, rows, independent, i, vels):
    """Coefficients c_j(q) with mu_i = sum_j c_j mu_j over the independent rows.

    Solves the square subsystem on the k velocity columns where the rows are
    best conditioned at a sample point (an overdetermined symbolic solve
    would miss trigonometric identities), then tidies each coefficient.
    """
    if not independent:
        return {}
    A = mu.extract(independent, list(range(mu.cols)))  # k x n
    rng = np.random.default_rng(VALIDATION_SEED + 3)
    for _ in range(8):  # a point where the rows are finite and real (log(x) at x > 0)
        sample = {s: rng.uniform(*STATE_BOX) for s in A.free_symbols}
        An = _real(np.array(A.xreplace(sample).evalf(), dtype=complex))
        if np.all(np.isfinite(An)):
            break
    import scipy.linalg

    cols = sorted(scipy.linalg.qr(An, pivoting=True)[2][: len(independent)])
    block = A.extract(list(range(len(independent))), cols)  # k x k, invertible
    target = mu.extract([i], cols)
    coeffs = block.T.LUsolve(target.T)
    out = {}
    for j, c in zip(independent, coeffs):
        c = sp.trigsimp(sp.cancel(c))
        if c != 0:
            out[j] = c
    return out


def _vanishes_at(expr, points, tol=1e-9):
    """True when ``expr`` is numerically zero at every sample point where it is finite
    (and at one at least)."""
    finite = 0
    for pt in points:
        try:
            value = complex(sp.sympify(sp.sympify(expr).xreplace(pt)).evalf())
        except (TypeError, ValueError):  # undefined there: says nothing
            continue
        if not (np.isfinite(value.real) and np.isfinite(value.imag)):
            continue
        finite += 1
        if abs(value) > tol * max(1.0, abs(value)):
            return False
    return finite > 0


def singular_rank(system) -> int | None:
    """The generic rank of W = d2L/dv dv when it is below n (exact for a constant W, else
    the largest at seeded points, confirmed in extended precision), None when W is
    invertible."""
    W = system.hessian
    n = system.n
    if not W.free_symbols:
        rank = W.rank()
        return rank if rank < n else None
    rng = np.random.default_rng(VALIDATION_SEED + 1)
    points, samples = finite_samples(W, system, rng, ["lagrangian"] * n)
    ranks = [float_rank(S) for S in samples]
    if max(ranks) < n:
        # A float64 deficiency may come from the units (m = 1e-16): confirm it.
        ranks = precise_ranks(W, points, [list(range(n))])
    return max(ranks) if max(ranks) < n else None


def singular_message(system, rank: int) -> str:
    """``lagrangian: the Hessian W ... is singular (rank r of n; null direction(s) ...)``:
    the kernel of W named (a symbolic nullspace: formed only for the message)."""
    W = sp.hessian(system.lagrangian, system.velocities)  # as the message always showed it
    try:
        null = W.nullspace(simplify=True) if W.free_symbols else W.nullspace()
    except BudgetExceeded:
        raise
    except Exception:  # pragma: no cover - sympy failure; message still useful
        null = []
    return _singular_message(W, rank, null)


def _singular_message(W, rank, null):
    if len(null) == 1:
        direction = f"; null direction {list(null[0])}"
    elif null:  # every direction of the kernel: one alone would hide the others
        direction = f"; null directions {', '.join(str(list(v)) for v in null)}"
    else:
        direction = ""
    return (
        f"lagrangian: the Hessian W = d2L/dv dv is singular (rank {rank} of {W.rows}"
        f"{direction})"
    )
