"""The verdict that holds at the system's parameter values.

Plain ``nhham classify`` answers here: the ordinary classification (parameters as
indeterminates where it decides symbolically), the data its decisions rest on checked
at the given values, and the classification run again where the values satisfy an
exceptional condition.
"""

from __future__ import annotations

import dataclasses
import math

import sympy as sp

from nhham.hamiltonian.classification import classify_constraints
from nhham.lagrangian.analysis import analyze_constraints
from nhham.lagrangian.exceptional import (
    POINTS,
    ExceptionalData,
    exceptional_components,
    exceptional_conditions,
)
from nhham.lagrangian.engine import Policy, policy_of
from nhham.settings import SEED, check_options
from nhham.progress import SLOW, part
from nhham.verdict.results import MAX_DEPTH, NEAR, ValuesVerdict, Verdict, exact_value
from nhham.verdict.substitution import branches, compose, rebuild

__all__ = ["classification_at_values", "classified", "examine"]

def classification_at_values(system, *, max_depth: int = MAX_DEPTH, precision: int | None = None,
                             seed: int = SEED, near: float = NEAR,
                             points: int = POINTS,
                             policy: Policy | None = None) -> ValuesVerdict:
    """The verdict that holds at the system's parameter values.

    The ordinary classification treats parameters as indeterminates wherever it
    decides symbolically. Here the data those decisions rest on are checked at the
    given values (exactly, the values read as decimals): when the values satisfy an
    exceptional condition, the condition is substituted (solved for a parameter with
    a value) and the classification is run again, up to ``max_depth`` times.
    Parameters without values stay generic.

    Parameters
    ----------
    system : nhham.System
    max_depth, near, points
        As in :func:`nhham.verdict.parametric.parametric_classification`.
    precision, seed : optional
        Deprecated (a ``DeprecationWarning``; removed in the next release): give them in
        ``policy``.
    policy : Policy, optional
        Every setting of the decisions (default ``Policy()``); its
        ``symbolic_values_size`` bounds n + m up to which the condition the values
        satisfy is named with the parameters kept symbolic.

    Returns
    -------
    ValuesVerdict

    Examples
    --------
    >>> import nhham
    >>> system = nhham.System(["q1", "q2", "q3"], "(a*q1_dot**2 + q2_dot**2 - q3_dot**2)/2",
    ...                       ["q2_dot + b*q3_dot"], parameters={"a": 1.0, "b": 1.0})
    >>> at = nhham.classification_at_values(system)     # b = 1: C = -(1 - b**2) = 0
    >>> at.verdict.status, at.generic.status, at.conditions
    ('underdetermined', 'determined', (b - 1,))
    """
    check_options("classification_at_values", near=near, max_depth=max_depth, points=points)
    policy = policy_of(policy, "classification_at_values", precision=precision, seed=seed)
    seed = policy.seed
    valued = tuple(p for p in system.parameters if p in system.parameter_values)
    opts = dict(policy=policy, points=points, near=near)
    values = {p: system.parameter_values[p] for p in valued}
    exact = {p: exact_value(v) for p, v in values.items()}
    generic, _, notes, hits, close = examine(system, (), values=values, **opts)
    notes = list(notes)
    warnings = _close_warnings(close, values) + _special_angle_warnings(system, values)
    current, verdict = system, generic
    conditions: list = []
    substitution: dict = {}
    for depth in range(max_depth + 1):
        if not hits:
            break
        if depth == max_depth:
            warnings.append(f"depth bound {max_depth} hit: the values are also where "
                            + "; ".join(r for r, _ in hits) + " (not examined further)")
            break
        left = [p for p in current.parameters if p in values]
        involved = tuple(dict.fromkeys(p for _, inv in hits for p in inv if p in left))
        branch: dict | None = None
        eqs: tuple = ()
        if involved and current.n + current.m <= policy.symbolic_values_size:
            comps = exceptional_conditions(verdict.analysis, involved, seed=seed,
                                           points=points)
            hit = next((c for c in comps if all(
                e.free_symbols <= set(exact) and e.xreplace(exact) == 0
                for e in c.equations)), None)
            if hit is not None:
                branch = next((b for b in branches(hit.equations, involved, {})
                               if all(sp.simplify(v.xreplace(exact) - exact[p]) == 0
                                      for p, v in b.items())), None)
                eqs = hit.equations
        if branch is None:
            fix = involved or tuple(left)
            branch = {p: exact[p] for p in fix}
            eqs = tuple(p - exact[p] for p in fix)
        substitution = compose(substitution, branch)
        conditions += [eq for eq in eqs if eq not in conditions]
        spec = rebuild(system, substitution, values)
        if isinstance(spec, Verdict):
            verdict, current = spec, None
            break
        current = spec
        rest = {p: v for p, v in values.items() if p not in substitution}
        verdict, _, more, hits, close = examine(spec, (), values=rest, **opts)
        notes += more
        warnings += _close_warnings(close, rest)
    if conditions and generic.analysis is not None:
        # The generic verdict, not the one at the values: a Frobenius term that is a
        # nonzero function vanishing at the values left ``integrable`` undecided there.
        generic = dataclasses.replace(generic,
                                      integrable=generic.analysis.integrability.generic)
    return ValuesVerdict(verdict, generic, tuple(conditions),
                         current if current is not None else system,
                         tuple(dict.fromkeys(warnings + notes)))


def _special_angle_warnings(system, values) -> list:
    """The angle parameter answered on the circle (:func:`~nhham.lagrangian.points.
    circle_parameters`) when its value is within rounding of a multiple of pi/2, where
    its sine or cosine vanishes: the decimal is answered as given, which may not be the
    angle meant (a scene cannot write pi/2 exactly)."""
    from nhham.lagrangian.points import circle_parameters

    out = []
    for p in circle_parameters(system):
        value = float(values[p])
        k = round(value / (math.pi / 2))
        # The decimal as written against k pi/2, in 30 digits (in doubles the gap is 0).
        gap = float(abs(sp.Rational(str(value)) - k * sp.pi / 2).evalf(30))
        if gap <= 1e-12 * max(1.0, abs(value)):
            which = "cos" if k % 2 else "sin"
            out.append(f"the parameter {p.name} = {value!r} is within {gap:.1e} of "
                       f"{k}*pi/2, where {which}({p.name}) vanishes: the verdict is the one at "
                       f"the decimal as given, where it does not; at {k}*pi/2 it may differ "
                       f"(`nhham classify --parametric` lists the special cases)")
    return out


def _close_warnings(close, values) -> list:
    names = ", ".join(f"{p.name} = {v}" for p, v in values.items())
    return [f"the parameter values {names} lie within relative distance {d:.1e} of values "
            f"where {reason}: the system is nearly singular there and numbers will be "
            f"ill-conditioned" for reason, d in close]


# ================================================================= one run
def classified(system, *, policy, points):
    """The ordinary classification of ``system`` (with the classes of its final
    constraints on T*Q, :func:`~nhham.hamiltonian.classification.classify_constraints`) and
    the data of its decisions.

    Returns (Verdict, ExceptionalData): the data evaluate, when asked, what each generic
    decision assumed nonzero (:mod:`nhham.lagrangian.exceptional`).
    """
    with part("constraint algorithm on TQ (stages, ranks on M_k)", after=SLOW):
        analysis = analyze_constraints(system, policy=policy)
    with part("integrability (Frobenius)", after=SLOW):
        integrable = analysis.integrable
    cls = None
    if analysis.status != "inconsistent":
        with part("first and second class on T*Q (brackets of the final constraints)", after=SLOW):
            cls = classify_constraints(analysis, policy=policy)
    # The second-class set the classification chose (for generic parameters when it
    # decided symbolically): at values where B drops rank its minor is the datum.
    second = (tuple(cls.second_class_indices) if cls is not None
              and tuple(cls.labels) == tuple(analysis.final_labels) else None)
    data = ExceptionalData(system, analysis, policy.seed, points, second_class=second)
    first = second = None
    if cls is not None:
        first, second = int(cls.first_class), int(cls.second_class)
    verdict = Verdict(
        status=analysis.status, regular=bool(analysis.regular), rank_C=int(analysis.rank_C),
        stages=len(analysis.stages), free_multipliers=int(analysis.free_multipliers),
        integrable=integrable, first_class=first, second_class=second,
        redundant=tuple(d.label for d in analysis.dropped),
        final_constraints=len(analysis.final_constraints), dimension=analysis.dimension,
        system=system, analysis=analysis, classes=cls)
    return verdict, data


def examine(system, params, *, policy, points, values=None, near=NEAR):
    """The ordinary classification of ``system`` (:func:`classified`) and the data of its
    decisions.

    Returns (Verdict, conditions, notes, hits, close): with ``params`` the exceptional
    conditions in those parameters (kept symbolic); with ``values`` the data that
    vanish at those exact values (``hits``) and those within relative distance
    ``near`` of vanishing (``close``).
    """
    verdict, data = classified(system, policy=policy, points=points)
    comps, hits, close = (), [], []
    with part("exceptional parameter values (where a decision's datum vanishes)"):
        if params:
            comps = exceptional_components(data.symbolic(tuple(params)), tuple(params))
        if values:
            hits, close = data.at_values(values, near)
    return verdict, comps, data.notes, hits, close
