"""Verdicts for every parameter value: where the classification changes.

The exceptional sets of the generic decisions (:mod:`nhham.lagrangian.exceptional`)
are explored in the manner of comprehensive Gröbner systems: every component is
*verified*: its condition is substituted into the system (solved for a parameter when
linear, else by ``sympy.solve``, real branches only) and the ordinary classification is
run there, recursively, so a spurious component can only produce a case that repeats
its parent's verdict, and such cases are dropped.

Conditions with no real solution under the parameters' declared signs (``positive=``
names, or sympy assumptions on the parameter symbols) are dropped and reported.
"""

from __future__ import annotations

import math
import time
from types import MappingProxyType
from typing import Callable, Sequence

import sympy as sp

from nhham.errors import BudgetExceeded, InputError
from nhham.lagrangian.exceptional import POINTS
from nhham.lagrangian.engine import Policy, policy_of
from nhham.settings import SEED, check_options
from nhham.system.expressions import short
from nhham.verdict.results import (
    MAX_DEPTH,
    NEAR,
    Case,
    ParametricVerdict,
    Verdict,
    exact_value,
)
from nhham.verdict.substitution import branches, canonical, compose, rebuild
from nhham.verdict.values import examine

__all__ = ["parametric_classification", "classifying_parameters"]


def parametric_classification(system, *, positive: Sequence = (),
                              max_depth: int = MAX_DEPTH,
                              precision: int | None = None, seed: int = SEED,
                              near: float = NEAR, points: int = POINTS,
                              policy: Policy | None = None, symbolic: Sequence | None = None,
                              progress: Callable[[str, str], None] | None = None
                              ) -> ParametricVerdict:
    """The verdict for generic parameters and every case where it changes.

    Parameters
    ----------
    system : nhham.System
        Parameter values, if any, are ignored for the cases (every parameter is
        treated as an indeterminate) and used only to place the system in a case.
    positive : sequence of str or sympy.Symbol, optional
        Parameters declared positive (masses, lengths); parameter symbols carrying
        sympy sign assumptions count as declared too.
    max_depth : int, optional
        Bound on the nesting of cases (a note says when it was hit).
    precision, seed : optional
        Deprecated (a ``DeprecationWarning``; removed in the next release): give them in
        ``policy``.
    near : float, optional
        Relative distance to an exceptional set below which the values are warned
        about.
    points : int, optional
        Exact points per decision datum.
    policy : Policy, optional
        Every setting of the decisions (:class:`~nhham.lagrangian.engine.Policy`);
        default ``Policy()``.
    symbolic : sequence of str or sympy.Symbol, optional
        The parameters kept symbolic; every other one is held at its value (it must have
        one) for the whole exploration. None (default): every parameter symbolic.
        :func:`classifying_parameters` names those that can change the verdict where C is
        regular.
    progress : callable, optional
        ``progress(run, note)`` before each run of the classification: ``run`` names it
        (``"generic run"``, ``"run 3: b - 1 = 0"``), ``note`` tells the runs done, their
        time and the estimated time of the runs known to be pending.

    Returns
    -------
    ParametricVerdict

    Raises
    ------
    InputError
        On a ``positive`` name that is not a parameter of the system, or a bad
        ``max_depth``/``near``.

    Examples
    --------
    >>> import nhham
    >>> system = nhham.System(["q1", "q2", "q3"], "(a*q1_dot**2 + q2_dot**2 - q3_dot**2)/2",
    ...                       ["q2_dot + b*q3_dot"], parameters={"a": 1.0, "b": 1.0})
    >>> verdicts = nhham.parametric_classification(system, positive=["a"])
    >>> verdicts.generic.status          # C = -(1 - b**2) by hand
    'determined'
    >>> [(str(case.conditions[0]), case.verdict.status) for case in verdicts.cases]
    [('b - 1', 'underdetermined'), ('b + 1', 'underdetermined')]
    >>> verdicts.scene_case              # a = b = 1
    0
    """
    # the inputs and t are not split into cases: a verdict holds for generic inputs
    declared = _declared_positive(system, positive)
    check_options("parametric_classification", near=near, max_depth=max_depth, points=points)
    policy = policy_of(policy, "parametric_classification", precision=precision, seed=seed)
    held = _held_values(system, symbolic)
    values = {p: v for p, v in system.parameter_values.items() if p not in held}
    original, system = system, _holding(system, held)
    params = tuple(system.declared_parameters)
    declared = [p for p in declared if p in params]
    opts = dict(policy=policy, points=points)
    base = rebuild(system, {}, None)
    signs = _sign_dummies(params, declared)
    clock = _Clock(progress)
    clock.start("generic run")
    generic, comps, notes, _, _ = examine(base, params, **opts)
    clock.done(len(comps))
    notes = list(notes)
    nodes, dropped, seen = [], [], set()

    def visit(sysm, sub, conditions, reasons_here, verdict_here, comps, depth):
        for comp in comps:
            clock.skip()  # this component is no longer pending (its runs are counted on)
            full = tuple(conditions) + tuple(comp.equations)
            why = _no_real_solution(comp.equations, signs)
            if why:
                dropped.append((full, why))
                continue
            for branch in branches(comp.equations, tuple(sysm.declared_parameters), signs):
                total = compose(sub, branch)
                why = _bad_substitution(total, signs)
                if why:
                    dropped.append((full, why))
                    continue
                key = canonical(total)
                if key in seen:
                    continue
                seen.add(key)
                spec = rebuild(system, total, None)
                if isinstance(spec, Verdict):
                    nodes.append((full, total, spec, verdict_here, comp.reasons))
                    continue
                remaining = tuple(p for p in params if p not in total)
                clock.start("run " + " and ".join(f"{short(e)} = 0" for e in full))
                try:
                    verdict, sub_comps, sub_notes, _, _ = examine(spec, remaining, **opts)
                except InputError as exc:  # this case only (a secondary constraint in an
                    # input): the other cases stand; BudgetExceeded is no InputError
                    clock.done(0)
                    nodes.append((full, total, _not_classified(exc), verdict_here,
                                  comp.reasons))
                    continue
                clock.done(len(sub_comps) if depth + 1 < max_depth else 0)
                notes.extend(sub_notes)
                nodes.append((full, total, verdict, verdict_here, comp.reasons))
                if depth + 1 < max_depth:
                    visit(spec, total, full, comp.reasons, verdict, sub_comps, depth + 1)
                elif sub_comps:
                    notes.append(
                        f"depth bound {max_depth} hit: below "
                        + ", ".join(f"{short(e)} = 0" for e in full)
                        + " further exceptional sets were not explored ("
                        + "; ".join(c.describe() for c in sub_comps) + ")")

    visit(base, {}, (), (), generic, comps, 0)
    cases = _order_cases(nodes)
    notes += _held_note(original, held, [generic] + [c.verdict for c in cases])
    scene_case, warnings = None, []
    if values:
        for i, case in enumerate(cases):
            if case.holds_at(values):
                scene_case = i
                break
        warnings = _near_warnings([(c.conditions, c.verdict) for c in cases], values, near)
    return ParametricVerdict(
        generic=generic, cases=tuple(cases), scene_case=scene_case,
        dropped=tuple(_dedupe(dropped)), notes=tuple(dict.fromkeys(notes)),
        warnings=tuple(warnings), parameters=params, positive=tuple(declared),
        values=MappingProxyType(values), held=MappingProxyType(
            {p: original.parameter_values[p] for p in held}))


def _not_classified(exc) -> Verdict:
    """The verdict of a case that nhham cannot classify (status ``invalid``, the reason)."""
    return Verdict(status="invalid", regular=None, rank_C=None, stages=0, free_multipliers=0,
                   integrable=None, first_class=None, second_class=None,
                   note=f"not classified in this case: {exc}")


def classifying_parameters(system) -> tuple:
    """The parameters that enter L, the affine or the holonomic constraints.

    Only they can change the verdict where C is regular on M_1: the rank of C, M_1, the
    integrability and the classes are formed from W, mu and the holonomic constraints. A
    parameter entering only the forces or the dissipation enters the tangency equations,
    which decide the verdict where C is singular (the secondary constraints); one that
    enters only a control law does not enter the system at all.
    """
    used = set(sp.sympify(system.lagrangian).free_symbols)
    for e in tuple(system.constraints) + tuple(system.holonomic):
        used |= sp.sympify(e).free_symbols
    return tuple(p for p in system.declared_parameters if p in used)


def _held_note(system, held, verdicts) -> list:
    """A note when a held parameter could change a verdict: one entering the forces or the
    dissipation, where C is singular (there they enter the secondary constraints)."""
    forced = set(sp.sympify(system.dissipation).free_symbols)
    for f in system.forces:
        forced |= sp.sympify(f).free_symbols
    names = sorted(p.name for p in held if p in forced)
    if not names or all(v.regular is not False for v in verdicts):
        return []
    return [f"C is singular in a verdict above, where the forces enter the secondary "
            f"constraints: the held {', '.join(names)} could change it there (keep "
            f"{'it' if len(names) == 1 else 'them'} symbolic: symbolic=, the command's "
            f"--symbolic)"]


def _held_values(system, symbolic) -> dict:
    """Parameter -> its value, for the parameters not in ``symbolic`` (None: none held)."""
    if symbolic is None:
        return {}
    by_name = {p.name: p for p in system.declared_parameters}
    names = [s.name if isinstance(s, sp.Symbol) else str(s) for s in symbolic]
    bad = [n for n in names if n not in by_name]
    if bad:
        raise InputError(f"symbolic: {', '.join(map(repr, bad))} "
                         f"{'is not a parameter' if len(bad) == 1 else 'are not parameters'} "
                         f"of the system (parameters: {', '.join(sorted(by_name)) or 'none'})",
                         key="symbolic")
    held = [p for p in system.declared_parameters if p.name not in names]
    missing = [p.name for p in held if p not in system.parameter_values]
    if missing:
        raise InputError(f"symbolic: {', '.join(map(repr, missing))} "
                         f"{'has' if len(missing) == 1 else 'have'} no value to be held at; "
                         f"keep {'it' if len(missing) == 1 else 'them'} symbolic",
                         key="symbolic")
    return {p: system.parameter_values[p] for p in held}


def _holding(system, held):
    """The system with the held parameters substituted (their exact decimal values)."""
    if not held:
        return system
    spec = rebuild(system, {p: exact_value(v) for p, v in held.items()},
                   {p: v for p, v in system.parameter_values.items() if p not in held})
    if isinstance(spec, Verdict):
        raise InputError(f"at the values of the held parameters "
                         f"{', '.join(f'{p.name} = {v}' for p, v in held.items())} "
                         f"{spec.note}", key="symbolic")
    return spec


class _Clock:
    """Tells ``progress`` of each run: the runs done, their time, and an estimate of
    what the runs known to be pending will take (more may appear below them)."""

    def __init__(self, progress):
        self.progress, self.runs, self.pending = progress, 0, 0
        self.begin = time.monotonic()

    def start(self, what: str) -> None:
        if self.progress is None:
            return
        spent = time.monotonic() - self.begin
        note = f"{self.runs} run{'s' if self.runs != 1 else ''} done in {spent:.1f} s"
        if self.runs:  # this run and those pending, at the mean time of a run so far
            note += (f"; about {spent / self.runs * (self.pending + 1):.0f} s for this run "
                     f"and the {self.pending} more known")
        self.progress(what, note)

    def done(self, found: int) -> None:
        self.runs += 1
        self.pending += found

    def skip(self) -> None:
        self.pending = max(self.pending - 1, 0)


def _distance_to_zero(expr, at, syms) -> float:
    """|e| / |grad e| at the exact point ``at``, formed exactly before it becomes a
    float (a polynomial of high degree in large values would overflow float64)."""
    grad2 = sum(sp.diff(expr, p).xreplace(at) ** 2 for p in syms)
    if not grad2:
        return math.inf
    try:
        return math.sqrt(float(expr.xreplace(at) ** 2 / grad2))
    except OverflowError:
        return math.inf


def _declared_positive(system, positive) -> list:
    by_name = {p.name: p for p in system.declared_parameters}
    out, bad = [], []
    for item in positive:
        name = item.name if isinstance(item, sp.Symbol) else str(item)
        if name not in by_name:
            bad.append(name)
        elif by_name[name] not in out:
            out.append(by_name[name])
    if bad:
        raise InputError(f"positive: {', '.join(repr(b) for b in bad)} "
                         f"{'is not a parameter' if len(bad) == 1 else 'are not parameters'} "
                         f"of the system (parameters: "
                         f"{', '.join(sorted(by_name)) or 'none'})")
    for p in system.declared_parameters:
        if p.is_positive and p not in out:
            out.append(p)
    return out


def _sign_dummies(params, positive) -> dict:
    """Parameter -> a real Dummy carrying its declared sign."""
    out = {}
    for p in params:
        kw = {"real": True}
        if p in positive:
            kw["positive"] = True
        for name in ("negative", "nonnegative", "nonpositive"):
            if getattr(p, f"is_{name}"):
                kw[name] = True
        out[p] = sp.Dummy(p.name, **kw)
    return out


def _no_real_solution(eqs, signs) -> str | None:
    """Why equations in the parameters have no real solution under the signs, else None."""
    for e in eqs:
        d = sp.sympify(e).xreplace(signs)
        try:
            definite = bool(d.is_positive) or bool(d.is_negative)
        except BudgetExceeded:  # an expiry is not an undecided sign
            raise
        except Exception:  # pragma: no cover
            definite = False
        if definite:
            decl = sorted((s.name for s in sp.sympify(e).free_symbols
                           if signs.get(s) is not None and signs[s].is_positive),
                          key=str)
            return (f"{short(e)} never vanishes for real parameters"
                    + (f" with {', '.join(n + ' > 0' for n in decl)}" if decl else ""))
    return None


def _bad_substitution(sub, signs) -> str | None:
    for p, v in sub.items():
        d = sp.sympify(v).xreplace(signs)
        if d.is_real is False:
            return f"{p.name} = {short(v)} is not real"
        s = signs.get(p)
        if s is not None and s.is_positive and d.is_nonpositive:
            return f"{p.name} = {short(v)} contradicts {p.name} > 0"
    return None


def _order_cases(nodes) -> list:
    """Cases, invalid ones and then the most specific first, each with the inequations
    excluding earlier ones.

    A node whose verdict equals the verdict of the set containing it (its parent) is
    not a case of its own; its sub-cases are kept.
    """
    kept = [(full, sub, v, why) for full, sub, v, parent, why in nodes if v != parent]
    # Where nhham does not apply (singular W) holds on the whole set, whatever else
    # holds there: those cases first; then the most specific first.
    kept.sort(key=lambda t: (t[2].status != "invalid", -len(t[1])))
    # A case whose points would fall, without it, into a case with the same verdict is
    # dropped: the first later case containing it, with no case in between meeting it.
    j = 0
    while j < len(kept):
        full, sub, verdict, _ = kept[j]
        fallback = None
        for k in range(j + 1, len(kept)):
            extra = _restricted(kept[k][0], sub)
            if any(e.is_number and e != 0 for e in extra):
                continue  # disjoint
            if all(e == 0 for e in extra):
                fallback = kept[k][2]
                break
            fallback = False  # meets part of it: keep the case
            break
        if fallback is not None and fallback is not False and fallback == verdict:
            del kept[j]
        else:
            j += 1
    cases: list = []
    for full, sub, verdict, why in kept:
        excluding = []
        for earlier in cases:
            extra = _restricted(earlier.conditions, sub)
            if any(e.is_number and e != 0 for e in extra):
                continue  # disjoint
            extra = [e for e in extra if e != 0]
            if not extra:
                continue
            excluding.append(extra[0] if len(extra) == 1
                             else sp.Add(*[e ** 2 for e in extra]))
        cases.append(Case(conditions=tuple(full), excluding=tuple(dict.fromkeys(excluding)),
                          verdict=verdict, substitution=MappingProxyType(dict(sub)),
                          reasons=tuple(why)))
    return cases


def _restricted(conditions, sub) -> list:
    """Conditions restricted to a case's set (its substitution applied), factored."""
    return [sp.factor(sp.expand(sp.sympify(e).xreplace(sub))) for e in conditions]


def _near_warnings(conds, values, near) -> list:
    """Warnings for values within relative distance ``near`` of a condition's set."""
    out: list = []
    if not near:
        return out
    for eqs, _ in conds:
        syms = set().union(*[sp.sympify(e).free_symbols for e in eqs]) if eqs else set()
        if not syms or not syms <= set(values):
            continue
        at = {p: exact_value(values[p]) for p in syms}
        if all(sp.sympify(e).xreplace(at) == 0 for e in eqs):
            continue
        scale = math.hypot(*(float(at[p]) for p in syms)) or 1.0
        dist = max(_distance_to_zero(sp.sympify(e), at, syms) for e in eqs)
        rel = dist / scale
        if rel < near:
            out.append("the parameter values "
                       + ", ".join(f"{p.name} = {values[p]}" for p in sorted(syms, key=str))
                       + f" lie within relative distance {rel:.1e} of the exceptional set "
                       + ", ".join(f"{short(e)} = 0" for e in eqs)
                       + ": the system is nearly singular there and numbers will be "
                         "ill-conditioned")
    return out


def _dedupe(items) -> list:
    """One entry per reason (the shortest conditions that gave it)."""
    best: dict = {}
    for eqs, why in items:
        if why not in best or len(eqs) < len(best[why]):
            best[why] = tuple(eqs)
    return [(eqs, why) for why, eqs in best.items()]


