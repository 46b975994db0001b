"""The Dirac–Bergmann chain for every value of the parameters (``classify --parametric``).

The generic chain runs with the parameters symbolic (the others held at their values).
Where its answer rests on a function of the parameters alone being nonzero, the
answer may change where that function vanishes; those functions are

* the parameter factors of the determinant of each generation's regular block of
  ({chi_j, phi_a}) (the rank that fixed the multipliers),
* the parameter factors of the content of each consistency condition and new constraint
  (where it degenerates: to a constant, or to nothing),
* the parameter factors of det B_RR, the maximal second-class block on M_f,
* the parameter factors of det W_IJ (rank W drops).

Each factor f = 0 is solved for one parameter; the chain runs again there (to a depth
bound), and a case is kept where its answer (status, generations, classes, degrees of
freedom) differs from the one it refines.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import sympy as sp

from nhham.errors import BudgetExceeded, NhhamError
from nhham.lagrangian.algebra import cancel
from nhham.lagrangian.engine import Policy

if TYPE_CHECKING:
    from nhham.hamiltonian.dirac_bergmann import DiracBergmann

__all__ = ["SingularCase", "SingularParametric", "singular_parametric", "exceptional_factors"]


@dataclass(frozen=True)
class SingularCase:
    """One exceptional case: the equations that hold, the reasons, the chain there."""

    conditions: tuple
    reasons: tuple
    chain: "DiracBergmann | None"  # None when the run failed
    failure: str | None = None


@dataclass(frozen=True)
class SingularParametric:
    """The generic chain and the exceptional cases (frozen).

    Attributes
    ----------
    symbolic : tuple of sympy.Symbol
        The parameters kept symbolic.
    held : dict
        The others, at their values.
    generic : DiracBergmann
    cases : tuple of SingularCase
    seconds : float
    """

    symbolic: tuple
    held: dict
    generic: "DiracBergmann"
    cases: tuple
    seconds: float
    values: dict

    def scene_case(self) -> int | None:
        """The index of the last (most specific) case whose conditions hold at the scene's
        values, else None."""
        found = None
        for i, case in enumerate(self.cases):
            if self.values and all(_holds(c, self.values) for c in case.conditions):
                found = i
        return found


def _holds(condition, values) -> bool:
    try:
        exact = {s: sp.Float(v) for s, v in values.items()}
        value = complex(sp.sympify(sp.sympify(condition).xreplace(exact)).evalf())
    except (TypeError, ValueError):
        return False
    return abs(value) <= 1e-12


def summary(db) -> tuple:
    """What a case must differ in to be reported."""
    if not db.consistent:
        return ("inconsistent",)
    return (db.status, tuple(len(g) for g in db.generations), db.first_class, db.second_class,
            db.degrees_of_freedom)


def exceptional_factors(db) -> list:
    """[(factor, reason)]: the functions of the parameters alone whose nonvanishing the
    chain ``db`` used (module docstring), each irreducible factor once."""
    params = set(db.system.parameters)
    if not params:
        return []
    state = db.algebra.variables
    found: dict = {}

    def add(expr, reason):
        expr = sp.numer(sp.together(cancel(expr)))
        if expr == 0 or not expr.free_symbols & params:
            return
        try:
            _, factors = sp.factor_list(expr)
        except (sp.PolynomialError, NotImplementedError):
            return
        for f, _ in factors:
            if f.free_symbols and f.free_symbols <= params:
                found.setdefault(sp.expand(f), reason)

    def add_content(expr, reason):
        present = [s for s in state if s in expr.free_symbols]
        if not present:
            add(expr, reason)
            return
        try:
            poly = sp.Poly(sp.expand(sp.numer(sp.together(expr))), *present)
        except sp.PolynomialError:
            return
        coeffs = [c for c in poly.coeffs()]
        add(sp.gcd_list(coeffs) if len(coeffs) > 1 else coeffs[0], reason)

    for f in db.image.rank_drops:
        add(f, "rank W drops")
    for stage in db.run.stages:
        rows, cols = stage.block
        if rows:
            A, _ = db.run.rows(rows)
            index = [db.multipliers.index(s) for s in cols]
            add(A.extract(list(range(A.rows)), index).det(method="berkowitz"),
                f"the rank of generation {stage.index}'s brackets drops")
        for lab, c in zip(stage.new_labels, stage.new_constraints):
            add_content(c, f"{lab} degenerates")
        for lab, psi in stage.conditions:
            # the stored constraint drops the parameter factors of psi: read them here
            add_content(sp.sympify(psi), f"the condition from {lab} degenerates")
    classes = db.classes
    if classes is not None and classes.second_class_set:
        R = list(classes.second_class_indices)
        chis = db.run.final_constraints
        B = sp.Matrix(len(R), len(R), lambda i, j: db.algebra.bracket(chis[R[i]], chis[R[j]]))
        add(db.manifold.reduce(B.det(method="berkowitz")),
            "the second-class block loses rank")
    return list(found.items())


def _solutions(factor, positive) -> list:
    """[{parameter: value}] solving factor = 0 for the parameter of lowest degree."""
    syms = sorted(factor.free_symbols, key=lambda s: (sp.degree(factor, s), s.name))
    for s in syms:
        try:
            sols = sp.solve(factor, s)
        except NotImplementedError:
            continue
        out = []
        for v in sols:
            if v.is_real is False:
                continue
            if s.name in positive and v.is_number and not v > 0:
                continue
            out.append({s: v})
        return out
    return []


def singular_parametric(system, *, policy: Policy | None = None, symbolic=None,
                        positive=(), max_depth: int = 3, steps=None) -> SingularParametric:
    """The chain with the parameters symbolic, and the cases where its answer changes.

    Parameters
    ----------
    system : nhham.System
        A singular Lagrangian.
    symbolic : sequence of str, optional
        The parameters kept symbolic (default every declared one); the others are held.
    positive : sequence of str
        Parameters declared positive: a case that needs one <= 0 is not examined.
    max_depth : int
        Bound on the nesting of cases.

    Returns
    -------
    SingularParametric

    Examples
    --------
    The longitudinal Proca mode: m != 0 two second class, m = 0 two first class.

    >>> from nhham import System
    >>> from nhham.verdict.singular import singular_parametric
    >>> s = System(["A0", "Az"], "(Az_dot - k*A0)**2/2 - m**2*(Az**2 - A0**2)/2",
    ...            parameters={"k": 1.0, "m": 1.0})
    >>> pv = singular_parametric(s, symbolic=["m"])
    >>> pv.generic.second_class, [(c.conditions, c.chain.first_class) for c in pv.cases]
    (2, [((m,), 2)])
    """
    from nhham.hamiltonian.dirac_bergmann import dirac_bergmann, with_parameters

    start = time.perf_counter()
    policy = policy or Policy()
    declared = list(system.declared_parameters)
    names = [p.name for p in declared] if symbolic is None else list(symbolic)
    values = dict(system.parameter_values)
    held = {p: values[p] for p in declared if p.name not in names and p in values}
    base = with_parameters(system, symbolic=names)
    generic = dirac_bergmann(base, policy=policy)
    cases: list = []
    seen: set = set()

    def explore(db, conditions, sub, depth):
        if depth <= 0 or not db.consistent and not db.system.parameters:
            return
        for factor, reason in exceptional_factors(db):
            for sol in _solutions(factor, set(positive)):
                total = {**sub, **sol}
                key = tuple(sorted((s.name, sp.srepr(v)) for s, v in total.items()))
                if key in seen:
                    continue
                seen.add(key)
                conds = conditions + (sp.expand(next(iter(sol)) - next(iter(sol.values()))),)
                try:
                    at = with_parameters(system, total, symbolic=names)
                    chain = dirac_bergmann(at, policy=policy)
                except BudgetExceeded:
                    raise
                except NhhamError as exc:
                    cases.append(SingularCase(conds, (reason,), None, str(exc)))
                    continue
                if summary(chain) != summary(db):
                    cases.append(SingularCase(conds, (reason,), chain))
                explore(chain, conds, total, depth - 1)

    explore(generic, (), {}, max_depth)
    return SingularParametric(symbolic=tuple(s for s in declared if s.name in names),
                              held={p.name: v for p, v in held.items()}, generic=generic,
                              cases=tuple(cases), seconds=time.perf_counter() - start,
                              values=values)
