"""The Dirac bracket of the second-class constraints, and the Dirac flow against the
projected field P(X_H) on M_f (Section 6 of the paper).
"""

from __future__ import annotations

import math
import functools
from dataclasses import dataclass, field, replace

import numpy as np
import sympy as sp

from nhham.errors import ComputationError
from nhham.hamiltonian.brackets import DiracBracket
from nhham.hamiltonian.classes import ConstraintClasses
from nhham.hamiltonian.classification import classify_constraints, sample_matrix
from nhham.hamiltonian.dirac_points import DiracDifference
from nhham.hamiltonian.side import HamiltonianSide, hamiltonian_side
from nhham.lagrangian.engine import Policy, decide, policy_of
from nhham.lagrangian.algebra import block_inverse, cancel
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.submanifold import Submanifold
from nhham.settings import SEED
from nhham.system.evaluation import Backend
from nhham.system.expressions import short

__all__ = ["dirac_bracket", "DiracProjectedReport", "dirac_vs_projected"]


# ---------------------------------------------------------------- Dirac
def dirac_bracket(source, classes: ConstraintClasses | None = None, *,
                  on_manifold: bool = False, **classify_options) -> DiracBracket:
    """The Dirac bracket over the maximal second-class set of the final constraints.

    Parameters
    ----------
    source : System, HamiltonianSide, ConstraintAnalysis or ConstraintClasses
    classes : ConstraintClasses, optional
        A classification to use (default: computed, exact mode).
    on_manifold : bool
        False (default): B = {chi_a, chi_b} as functions on T*Q, blocks from
        its identically nonzero entries, so the Dirac bracket is a Poisson
        bracket wherever B is invertible. True: B reduced on M_f and blocks
        from the decisions on M_f (cheaper; valid on M_f only).
    **classify_options
        Passed to :func:`classify_constraints`.

    Returns
    -------
    DiracBracket

    Examples
    --------
    On the circle of the Cartesian pendulum, {x, p_x}_D = 1 - x**2/(x**2 + y**2).

    >>> import sympy as sp
    >>> from nhham import dirac_bracket, models
    >>> D = dirac_bracket(models.pendulum_cartesian())
    >>> x, y = D.algebra.coordinates
    >>> sp.simplify(D(x, D.algebra.momenta[0]))
    y**2/(x**2 + y**2)
    """
    if isinstance(source, ConstraintClasses):
        classes = source
    if classes is None:
        classify_options.setdefault("method", "exact")
        classes = classify_constraints(source, **classify_options)
    constraints, bracket_matrix, _ = _exact_parts(classes, "the Dirac bracket")
    side = classes.side
    R = list(classes.second_class_indices)
    chi = [constraints[a] for a in R]
    if on_manifold:
        B = bracket_matrix.extract(R, R)
        label_index = {lab: i for i, lab in enumerate(classes.second_class_set)}
        blocks = [[label_index[lab] for lab in blk if lab in label_index]
                  for blk in classes.blocks]
        blocks = [b for b in blocks if b]
        return DiracBracket(side.algebra, chi, blocks=blocks, matrix=B)
    return DiracBracket(side.algebra, chi)


def _exact_parts(classes: ConstraintClasses,
                 what: str) -> tuple[tuple, sp.Matrix, Submanifold]:
    """(chi in (q, p), B reduced on M_f, M_f) of an exact classification; only exact
    mode has them (at points and sampled: None)."""
    if classes.constraints is None or classes.bracket_matrix is None or classes.manifold is None:
        raise ComputationError(f"{what} needs the constraints in (q, p): classify with "
                               f"method='exact' (this classification: {classes.method!r})")
    return classes.constraints, classes.bracket_matrix, classes.manifold


@dataclass(frozen=True)
class DiracProjectedReport:
    """The Dirac-bracket flow of H against the projected field X on M_f.

    Attributes
    ----------
    equal : bool
        True when X_D - X vanishes on M_f (every component).
    difference : sympy.Matrix, shape (2n, 1), or None
        X_D - X reduced on M_f, in (q, p) (None in sampled mode).
    dirac_field, projected_field : sympy.Matrix, shape (2n, 1), or None
        X_D = (z -> {z, H}_D) and X = X_H + lambda^j Z_j^H on M_f (None in
        sampled mode), brought to normal form when first read: the comparison needs
        only their difference (two thirds of its cancellations went into them).
    decisions : tuple of Decision
        Per component of the difference: does it vanish on M_f.
    max_abs_difference : float
        Largest |X_D - X| at the seeded sample points of M_f (nan when compared
        exactly modulo p at exact points: F_p has no absolute value).
    samples : int
    notes : tuple of str
        Caveats (first-class constraints make the Dirac flow a gauge family).
    classes : ConstraintClasses
    components : tuple of str
        The (q, p) variables whose component of X_D - X is nonzero on M_f: those
        nonzero after reduction, or at an exact point (a proof); () when equal, and
        in sampled mode those above the tolerance at some point.
    """

    equal: bool
    difference: sp.Matrix | None
    decisions: tuple
    max_abs_difference: float
    samples: int
    notes: tuple
    classes: ConstraintClasses
    components: tuple = ()
    #: (X_H, the Dirac correction, the multipliers' term) on M_f, per variable.
    parts: tuple | None = field(default=None, repr=False, compare=False)

    @functools.cached_property
    def dirac_field(self) -> sp.Matrix | None:
        if self.parts is None:
            return None
        return sp.Matrix([cancel(x - c) for x, c, _ in zip(*self.parts)])

    @functools.cached_property
    def projected_field(self) -> sp.Matrix | None:
        if self.parts is None:
            return None
        return sp.Matrix([cancel(x + f) for x, _, f in zip(*self.parts)])

    def describe(self) -> str:
        if self.equal:
            d = self.decisions[0] if self.difference is None and self.decisions else None
            how = "" if d is None else ": " + d.detail + (
                f"; error <= {d.error_bound:.1e}" if d.method == "exact at points" else "")
            return ("the Dirac-bracket flow of H equals the projected (nonholonomic) field on "
                    "M_f" + how)
        if self.difference is None:
            return ("the Dirac-bracket flow of H is NOT the true dynamics on M_f: "
                    + self.decisions[0].detail)
        comps = [f"d/d{z}: {short(d, 160)}" for z, d in zip(self.classes.side.variables,
                                                              self.difference) if d != 0]
        cut = any(len(str(d)) > 160 for d in self.difference)
        return ("the Dirac-bracket flow of H is NOT the true dynamics on M_f; X_D - X = "
                + "; ".join(comps) + f" (max |X_D - X| = {self.max_abs_difference:.3g} at "
                f"{self.samples} sample points" + ("; whole expressions with --json or "
                                                    "--latex)" if cut else ")"))

    def to_dict(self) -> dict:
        return {"equal": self.equal,
                "difference": (None if self.difference is None
                               else [str(d) for d in self.difference]),
                "max_abs_difference": self.max_abs_difference,
                "samples": self.samples, "notes": list(self.notes),
                "components": list(self.components)}


def dirac_vs_projected(system, *, precision=None, samples=6, seed=SEED,
                       classes: ConstraintClasses | None = None, method: str = "auto",
                       tol: float | None = None,
                       side: HamiltonianSide | None = None,
                       policy: Policy | None = None) -> DiracProjectedReport:
    """Compare the Dirac-bracket flow of H with the true (projected) dynamics on M_f.

    For holonomic constraints the two agree on M_f; for truly nonholonomic
    constraints they do not (nonholonomic dynamics is not variational). The
    Dirac flow is taken over the maximal second-class set of the final
    constraints. Exact mode (an exact classification, and M_f flat or n <= 3):
    the difference X_D - X is reduced on M_f and decided per component, and
    evaluated at seeded points. Otherwise it is decided at exact points of M_f
    (over F_p where M_f is curved) by the decision engine: a component nonzero at
    one point is a proof that the flows differ, zero at every point is agreement
    with the error bound of the points
    (:class:`~nhham.hamiltonian.dirac_points.DiracDifference`). Sampled mode
    (``method="sampled"``, or no exact points): both fields are evaluated
    numerically at seeded points of M_f and the difference is decided there.
    ``difference`` is None except in exact mode.

    Parameters
    ----------
    system : nhham.System
        A regular system (C^H invertible on M_1).
    precision, samples, seed
        Settings of the sampled decisions.
    classes : ConstraintClasses, optional
        A classification to use; its method decides the mode.
    method : {"auto", "exact", "sampled"}
        As for :func:`classify_constraints`.
    tol : float, optional
        Relative tolerance of sampled decisions.
    side : HamiltonianSide, optional
        The T*Q side of ``system`` when the caller has it.
    policy : Policy, optional
        The settings of the decisions, instead of ``precision``, ``samples``, ``seed``
        and ``tol``.

    Returns
    -------
    DiracProjectedReport

    Examples
    --------
    A holonomic constraint: the Dirac flow is the true one. The sleigh's constraint is
    first class, so its Dirac bracket is the canonical one, whose flow ignores it.

    >>> from nhham import dirac_vs_projected, models
    >>> dirac_vs_projected(models.pendulum_cartesian()).equal
    True
    >>> dirac_vs_projected(models.chaplygin_sleigh()).equal
    False
    """
    policy = policy_of(policy, "dirac_vs_projected", precision=precision, samples=samples,
                       seed=seed, tol=tol)
    precision, samples, seed, tol = policy.precision, policy.samples, policy.seed, policy.tol
    if side is None:
        side = classes.side if classes is not None else hamiltonian_side(
            system, closed_form=True, policy=Policy(precision=precision, samples=samples,
                                                     seed=seed))
    if classes is None:
        # The Dirac bracket needs the class split and R, not the first-class combinations
        # in closed form (the longest part of a classification: 5 s of a four-bar's 6).
        classes = classify_constraints(side, method=method,
                                       policy=replace(policy, combination_size=0))
    symbolic = _symbolic(side, classes)
    if not symbolic and method != "sampled":
        report = _dirac_vs_projected_at_points(side, classes, policy)
        if report is not None:
            return report
    if not symbolic:
        return _dirac_vs_projected_sampled(side, classes, precision, samples, seed, tol)
    if not side.regular:
        raise ComputationError(
            "dirac_vs_projected: C^H is singular on M_1; the projected field is a family "
            "(see nhham.lagrangian.algorithm) and the comparison is defined for regular systems only")
    parts, diff = _fields_on_Mf(side, classes)
    _, _, Mf = _exact_parts(classes, "dirac_vs_projected")
    decisions = tuple(Mf.vanishes(d, tol=tol) for d in diff)
    reduced = sp.Matrix([0 if d.value else e for d, e in zip(decisions, diff)])
    notes = _gauge_note(classes)
    at, generic = _at_parameter_values(Mf, reduced, tol, side.variables)
    if at is not None:
        # The verdict is for the scene's values; the generic difference is a note.
        decisions, reduced = at
        notes += (f"X_D - X vanishes at the parameter values but not for generic values "
                  f"({generic})",)
    sampled = sample_matrix(Mf, reduced) if reduced.rows else []
    # A sample point on a singular set of the chart (the snakeboard at phi = +-pi/2)
    # gives no value: it is left out, not reported as an infinite difference.
    sampled = [S for S in sampled if np.all(np.isfinite(S))]
    worst = max((float(np.max(np.abs(S))) for S in sampled), default=0.0)
    return DiracProjectedReport(
        equal=all(d.value for d in decisions), difference=reduced, decisions=decisions,
        max_abs_difference=worst, samples=len(sampled), notes=notes, classes=classes,
        components=tuple(str(z) for z, e in zip(side.variables, reduced) if e != 0),
        parts=parts)


def _at_parameter_values(Mf, reduced, tol, variables):
    """((decisions, reduced difference) at the system's parameter values, the generic
    difference as text) when the values make a generically nonzero X_D - X vanish;
    else (None, None)."""
    values = Mf.system.exact_parameter_values
    if not values or all(e == 0 for e in reduced):
        return None, None
    at_values = [cancel(e.xreplace(values)) for e in reduced]
    decisions = tuple(Mf.vanishes(e, tol=tol) for e in at_values)
    if not all(d.value for d in decisions):
        return None, None
    generic = "; ".join(f"d/d{z}: {e}" for z, e in zip(variables, reduced) if e != 0)
    return (decisions, sp.zeros(*reduced.shape)), generic


def _gauge_note(classes) -> tuple:
    if not classes.first_class:
        return ()
    return (f"{classes.first_class} first-class constraint(s): the Dirac flow is then only "
            f"defined up to adding multiples of their Hamiltonian fields (gauge); the field "
            f"compared is {{z, H}}_D without such terms",)


def _dirac_minus_projected(be, num, hp, chis):
    """X_D - X at one point of the numeric layer (``be`` arithmetic), or None where C^H
    is singular (outside the domain of X).

    X_D = X_H - X_{chi_a} (B_RR^{-1})^{ab} ({chi_b, H} + d chi_b/dt) with
    X_chi = (chi_p, -chi_q), X = X_H + lambda^j Z_j^H.
    """
    try:
        X, _ = num.projected_field(be, hp)
    except (np.linalg.LinAlgError, ZeroDivisionError):
        return None
    XD = hp.X_H.copy()
    if chis:
        _, Gq, Gp = num.gradients(be, hp, chis)
        B = Gq @ Gp.T - Gp @ Gq.T
        y = be.solve(B, Gq @ hp.Hp - Gp @ hp.Hq + num.time_derivatives(be, hp, chis))
        XD = XD - np.concatenate([Gp.T @ y, -(Gq.T @ y)])
    return XD, X


def _symbolic(side, classes) -> bool:
    """X_D - X is formed symbolically where the classification was (exact) and M_f is
    flat or n <= 3; on a curved M_f of more coordinates, reducing the assembled fields
    takes minutes (a rotor on a sphere, n = 4: 43 s; with more coupling > 9 min) and the
    points over F_p answer in milliseconds."""
    if classes.method != "exact":
        return False
    return side.n <= 3 or not _tq_manifold(side, classes).curved


def _tq_manifold(side, classes) -> Submanifold:
    return Submanifold(side.system, tuple(classes.constraints_TQ), precision=side.precision,
                       samples=side.samples, seed=side.seed)


def _dirac_vs_projected_at_points(side, classes, policy):
    """X_D - X decided at exact points of M_f by the decision engine
    (:class:`~nhham.hamiltonian.dirac_points.DiracDifference`): a component nonzero at
    one point is a proof that the flows differ; zero at every point is "equal" with
    the error bound of the points. None where M_f has no exact points."""
    if not policy.exact:
        return None
    quantity = DiracDifference(side, classes.constraints_TQ, classes.second_class_indices)
    manifold = _tq_manifold(side, classes)
    verdict = decide(quantity, manifold, policy)
    if verdict is None:
        return None
    decision = verdict.decision
    return DiracProjectedReport(
        equal=bool(decision.value), difference=None,
        decisions=(decision,), max_abs_difference=math.nan, samples=decision.samples,
        notes=_gauge_note(classes), classes=classes, components=verdict.components)


def _dirac_vs_projected_sampled(side, classes, precision, samples, seed, tol):
    """X_D - X at seeded points of M_f from the numeric layer (no symbolic inverse).

    X_D = X_H - X_{chi_a} (B_RR^{-1})^{ab} {chi_b, H} with X_chi = (chi_p, -chi_q),
    X = X_H + lambda^j Z_j^H; R the maximal second-class set of ``classes``.
    """
    system = side.system
    be = Backend(precision)
    tol_ = be.default_tol() if tol is None else tol
    R = list(classes.second_class_indices)
    chis = [classes.constraints_TQ[a] for a in R]
    Mtq = Submanifold(system, classes.constraints_TQ, precision=precision, samples=samples,
                      seed=seed, exact=False)
    points, resid = Mtq.points()
    num = side.numeric
    worst, worst_rel, used, above = 0.0, 0.0, 0, set()
    with be.context():
        for x in points:
            got = _dirac_minus_projected(be, num, num.point_from_tq(be, x), chis)
            if got is None:
                continue  # C singular at this point: outside the domain of X
            XD, X = got
            d = float(be.norm(XD - X))
            scale = max(1.0, float(be.norm(X)), float(be.norm(XD)))
            worst, worst_rel, used = max(worst, d), max(worst_rel, d / scale), used + 1
            above |= {i for i, e in enumerate(XD - X) if float(abs(e)) > tol_ * scale}
    if not used:
        raise ComputationError("dirac_vs_projected: C^H is singular at every sample point")
    equal = worst_rel <= tol_
    decision = Decision(
        equal, "sampled",
        f"largest |X_D - X| {worst:.3g} (relative {worst_rel:.3g}) at {used} seeded points "
        f"of M_f, tolerance {tol_:g}", precision=be.label, samples=used, max_abs=worst,
        point_residual=resid)
    return DiracProjectedReport(
        equal=equal, difference=None,
        decisions=(decision,), max_abs_difference=worst, samples=used,
        notes=_gauge_note(classes), classes=classes,
        components=() if equal else tuple(str(side.variables[i]) for i in sorted(above)))


def _fields_on_Mf(side: HamiltonianSide, classes: ConstraintClasses):
    """((X_H, correction, multipliers' term) per variable, X_D - X) on M_f, assembled
    from factors reduced on M_f first (X_D = X_H - correction, X = X_H + the term).

    {z, H}_D = {z, H} - {z, chi_a} (B^{-1})^{ab} {chi_b, H} and
    X = X_H + Z_j^H lambda^j; reducing the small factors before multiplying
    keeps the expressions small (reducing the assembled fields is far slower).
    """
    constraints, bracket_matrix, Mf = _exact_parts(classes, "dirac_vs_projected")
    alg = side.algebra
    R = list(classes.second_class_indices)
    chi = [constraints[a] for a in R]
    B = bracket_matrix.extract(R, R)
    label_index = {lab: i for i, lab in enumerate(classes.second_class_set)}
    blocks = [[label_index[lab] for lab in blk if lab in label_index] for blk in classes.blocks]
    blocks = [b for b in blocks if b]
    inverses = [(blk, block_inverse(B.extract(blk, blk))) for blk in blocks]
    if side.system.has_forces:  # dchi(X_H + F^V): the Dirac projection of the forced field
        s = [Mf.reduce(cancel(sum((sp.diff(c, z) * X for z, X in zip(side.variables, side.X_H)),
                                  sp.S.Zero))) for c in chi]
    else:
        s = [Mf.reduce(alg.bracket(c, side.H)) for c in chi]
    time = side.system.time
    if time is not None:  # {chi_b, H} + d chi_b/dt: constraints moving with t (DESIGN.md §2)
        s = [cancel(e + Mf.reduce(sp.diff(c, time))) for e, c in zip(s, chi)]
    XH = [Mf.reduce(e) for e in side.X_H]
    lam = [Mf.reduce(e) for e in side.multipliers]
    Z = side.vertical_fields
    corrections, forces, diff = [], [], []
    for i, z in enumerate(side.variables):
        t = [Mf.reduce(alg.bracket(z, c)) for c in chi]
        corr = sp.S.Zero
        for blk, inv in inverses:
            for ia, a in enumerate(blk):
                if t[a] == 0:
                    continue
                for ib, b in enumerate(blk):
                    if inv[ia, ib] != 0 and s[b] != 0:
                        corr += t[a] * inv[ia, ib] * s[b]
        force = sum((Z[j, i] * lam[j] for j in range(side.m)), sp.S.Zero)
        corrections.append(corr)
        forces.append(force)
        diff.append(cancel(-corr - force))
    return (tuple(XH), tuple(corrections), tuple(forces)), sp.Matrix(diff)
