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

import dataclasses
import math
import time
from collections import deque
from contextlib import contextmanager
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Callable, Iterator, Sequence

import sympy as sp

from nhham.budget import remaining_time, time_budget
from nhham.errors import BudgetExceeded, InputError
from nhham.lagrangian.engine import Policy, policy_of
from nhham.lagrangian.components import split_components
from nhham.lagrangian.exceptional import POINTS
from nhham.progress import SLOW, part
from nhham.settings import SEED, check_options
from nhham.system.expressions import short
from nhham.verdict.results import (
    MAX_DEPTH,
    NEAR,
    Case,
    ParametricVerdict,
    SearchReport,
    Verdict,
    exact_value,
)
from nhham.verdict.substitution import branches, canonical, compose, rebuild
from nhham.verdict.values import classified

__all__ = ["parametric_classification", "classifying_parameters", "needed_parameters",
           "NEEDED", "REPORT_SHARE"]


def parametric_classification(system, *, positive: Sequence = (),
                              max_depth: int = MAX_DEPTH,
                              precision: int | None = None, seed: int = SEED,
                              near: float = NEAR, points: int = POINTS,
                              policy: Policy | None = None, symbolic=None,
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
    symbolic : sequence of str or sympy.Symbol, or NEEDED, optional
        The parameters kept symbolic; every other one is held at its value (it must have
        one) for the whole exploration. None (default): every parameter symbolic.
        :data:`NEEDED`: those that nhham knows can change the verdict
        (:func:`needed_parameters`): then a parameter entering only the forces or the
        dissipation is held unless C is singular in a verdict found with it held; where
        it is, the exploration is made again with it symbolic, when the time the first
        took fits in the budget in force (else a warning says so, with that estimate).
    progress : callable, optional
        ``progress(run, note)`` before each run of the classification: ``run`` names it
        (``"generic run"``, ``"run 3: b - 1 = 0"``), ``note`` tells the runs done, their
        time and the estimated time of the runs known to be pending.

    Returns
    -------
    ParametricVerdict
        Its ``search`` says whether the search for cases was complete. Within a budget
        (``nhham.time_budget``, the command's ``--budget``) the generic verdict is
        formed first; the search gets what is left but a share kept for the report
        (:data:`REPORT_SHARE`), follows the components of codimension 1 of every run
        first and solves the lower-dimensional ones (a lex Gröbner basis each) last,
        each with an equal share of the time then left. Cut by its budget, it keeps the
        cases found, names what was cut and why, and adds a warning.

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
    opts = dict(positive=declared, max_depth=max_depth, near=near,
                run=dict(policy=policy, points=points), progress=progress)
    if isinstance(symbolic, str) and symbolic == NEEDED:
        return _needed(system, opts)
    return _explore(system, _held_values(system, symbolic), **opts)


#: ``symbolic=NEEDED``: keep symbolic the parameters that can change the verdict.
NEEDED = "needed"
#: The share of the time a budget leaves after the generic verdict that the search for
#: cases does not take: the report of the verdicts found is made in it.
REPORT_SHARE = 0.1


def needed_parameters(system) -> tuple:
    """The parameters a parametric classification keeps symbolic first (``NEEDED``):
    :func:`classifying_parameters` and every parameter without a value (it cannot be
    held).

    Examples
    --------
    >>> import nhham
    >>> system = nhham.System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2", ["x_dot - a*y"],
    ...                       parameters={"m": 1.0, "a": 2.0, "c": 0.1},
    ...                       dissipation="c*y_dot**2/2")
    >>> needed_parameters(system)         # c enters the dissipation only
    (m, a)
    """
    keep = set(classifying_parameters(system))
    return tuple(p for p in system.declared_parameters
                 if p in keep or p not in system.parameter_values)


def _needed(system, opts) -> ParametricVerdict:
    """``symbolic=NEEDED``: held force parameters become symbolic where a verdict has C
    singular (there the forces enter the secondary constraints), when the time allows."""
    first = needed_parameters(system)
    pv = _explore(system, _held_values(system, first), held_note=False, **opts)
    forced = [p for p in pv.held if p in _force_parameters(system)]
    singular = _singular_verdicts(pv)
    if not forced or not singular:
        return pv
    names = ", ".join(p.name for p in forced)
    why = (f"{names} {'enters' if len(forced) == 1 else 'enter'} the forces, which enter "
           f"the secondary constraints where C is singular ({'; '.join(singular)})")
    # The runs again with them symbolic: at least the time these took.
    estimate, left = pv.search.seconds, remaining_time()
    room = left * (1 - REPORT_SHARE)
    held = f"{why}, but {'they were' if len(forced) > 1 else 'it was'} held: "
    insist = ("; give a larger budget (--budget) or --symbolic "
              + ",".join(p.name for p in first + tuple(forced)))
    if not pv.search.complete:
        return _with(pv, warnings=(f"{held}the runs with {names} held did not complete "
                                   f"(see the search's warning)" + insist,))
    if estimate > room:
        return _with(pv, warnings=(
            f"{held}keeping {'them' if len(forced) > 1 else 'it'} symbolic means the runs "
            f"again, about {estimate:.0f} s or more (the runs with {names} held took "
            f"{estimate:.1f} s), and {max(room, 0):.0f} s of the budget "
            f"{'is' if room >= 1 else 'was'} left for it" + insist,))
    cut = None
    try:
        with part(f"the runs again with {names} symbolic ({why})", f"about {estimate:.0f} s",
                  after=SLOW), time_budget(None if math.isinf(room) else room):
            again = _explore(system, _held_values(system, first + tuple(forced)), **opts)
        cut = again.search.warning()
    except BudgetExceeded as exc:  # its generic run did not end in the room left
        if remaining_time() <= 0:
            raise
        cut = f"{exc.part or 'the generic run'} ran out of the {room:.3g} s left"
    if cut:
        return _with(pv, warnings=(f"{why}; the runs again with {names} symbolic were cut "
                                   f"by the budget ({cut}), so "
                                   f"{'they are' if len(forced) > 1 else 'it is'} held "
                                   f"below",))
    again = dataclasses.replace(again, search=dataclasses.replace(
        again.search, seconds=pv.search.seconds + again.search.seconds))
    return _with(again, notes=(f"{names} kept symbolic: {why}",))


def _with(pv, warnings=(), notes=()) -> ParametricVerdict:
    """``pv`` with more warnings and notes."""
    return dataclasses.replace(pv, warnings=tuple(pv.warnings) + tuple(warnings),
                               notes=tuple(notes) + tuple(pv.notes))


def _singular_verdicts(pv) -> list:
    """Where C is singular: "for generic parameters" and the cases' conditions."""
    out = ["for generic parameters"] if pv.generic.regular is False else []
    return out + [" and ".join(f"{short(e)} = 0" for e in c.conditions)
                  for c in pv.cases if c.verdict.regular is False]


def _explore(original, held, *, positive, max_depth, near, run, progress, held_note=True
             ) -> ParametricVerdict:
    """The exploration with the parameters of ``held`` held at their values (``held_note``:
    with a note when one could change a verdict found)."""
    values = {p: v for p, v in original.parameter_values.items() if p not in held}
    system = _holding(original, held)
    params = tuple(system.declared_parameters)
    declared = [p for p in positive if p in params]
    base = rebuild(system, {}, None)
    clock = _Clock(progress)
    with clock.run("generic run"):  # the generic verdict comes first, whatever follows
        generic, data = classified(base, **run)
    search = _Search(system, params, _sign_dummies(params, declared), clock, run, max_depth)
    report = search.explore(_Node(base, {}, (), generic, 0), data)
    cases = _order_cases(search.nodes)
    notes = search.notes + (_held_note(original, held, [generic] + [c.verdict for c in cases])
                            if held_note else [])
    scene_case, warnings = None, []
    if values:
        for i, case in enumerate(cases):
            if case.holds_at(values):
                scene_case = i
                break
        warnings = _near_warnings([(c.conditions, c.verdict) for c in cases], values, near)
    cut = report.warning()
    return ParametricVerdict(
        generic=generic, cases=tuple(cases), scene_case=scene_case,
        dropped=tuple(_dedupe(search.dropped)), notes=tuple(dict.fromkeys(notes)),
        warnings=tuple(warnings) + ((cut,) if cut else ()), parameters=params,
        positive=tuple(declared), values=MappingProxyType(values),
        held=MappingProxyType({p: original.parameter_values[p] for p in held}),
        search=dataclasses.replace(report, seconds=clock.spent()))


@dataclass(frozen=True)
class _Node:
    """A verdict of the exploration: its system, the substitution and conditions that
    made it, and its depth (the generic run: 0)."""

    system: Any
    sub: dict
    conditions: tuple
    verdict: Verdict
    depth: int

    def name(self) -> str:
        return ("the generic run" if not self.conditions else
                "run " + " and ".join(f"{short(e)} = 0" for e in self.conditions))


class _Search:
    """The search for cases below the generic verdict: the verdicts found (``nodes``),
    what was dropped, the notes, and within a budget what it left pending."""

    def __init__(self, system, params, signs, clock, run, max_depth):
        self.system, self.params, self.signs = system, params, signs
        self.clock, self.run, self.max_depth = clock, run, max_depth
        self.nodes: list = []
        self.dropped: list = []
        self.notes: list = []
        self.seen: set = set()
        self.pending: dict = {}      # (id of the node, index) -> conditions, not examined
        self.lower: deque = deque()  # (node, LowerDimensional), solved last
        self.cut: list = []
        self.failed: list = []

    def explore(self, root, data) -> SearchReport:
        """Follow the components of every run from the generic one's ``data``, within
        what the budget in force leaves (less :data:`REPORT_SHARE`)."""
        left = remaining_time()
        allowed = None if math.isinf(left) else left * (1 - REPORT_SHARE)
        why = (None if allowed is None else
               f"its {allowed:.3g} s ran out: the budget in force left {left:.3g} s after "
               f"the generic run, {left - allowed:.2g} s of them kept for the report")
        try:
            # (left <= 0: the budget in force is running out; its expiry ends the command)
            with time_budget(None if allowed is None else max(allowed, 1e-3)):
                self.expand(root, data)
                while self.lower:
                    self.solve_lower(*self.lower.popleft())
        except BudgetExceeded as exc:
            if remaining_time() <= 0:  # the budget in force itself: nothing can be kept
                raise
            self.cut.append((exc.part or "the search for exceptional cases",
                             why or f"a budget ran out: {exc}"))
        unsolved = [f"{node.name()}: where {'; '.join(lower.reasons)} (codimension > 1)"
                    for node, lower in self.lower]
        return SearchReport(complete=not self.cut and not self.failed, allowed=allowed,
                            cut=tuple(self.cut), pending=tuple(self.pending.values()),
                            unsolved=tuple(unsolved), failed=tuple(self.failed))

    def expand(self, node, data) -> None:
        """The components of ``node``'s exceptional sets, followed (those of codimension
        1 now, the others queued) or, at the depth bound, noted."""
        remaining = tuple(p for p in self.params if p not in node.sub)
        comps: tuple = ()
        lower: tuple = ()
        with part(f"exceptional parameter values of {node.name()} (where a decision's "
                  f"datum vanishes)", after=SLOW):
            if remaining:
                comps, lower = split_components(data.symbolic(remaining), remaining)
        self.notes.extend(data.notes)
        if node.depth and node.depth >= self.max_depth:
            if comps or lower:
                self.notes.append(
                    f"depth bound {self.max_depth} hit: below "
                    + ", ".join(f"{short(e)} = 0" for e in node.conditions)
                    + " further exceptional sets were not explored ("
                    + "; ".join([c.describe() for c in comps]
                                + [f"where {'; '.join(x.reasons)} in codimension > 1"
                                   for x in lower]) + ")")
            return
        self.clock.found(len(comps))
        self.lower.extend((node, x) for x in lower)
        self.visit(node, comps)

    def solve_lower(self, node, lower) -> None:
        """The lower-dimensional components of one datum, with an equal share of the time
        left among the searches of their kind still queued; followed when found."""
        left = remaining_time()
        share = None if math.isinf(left) else left / (len(self.lower) + 1)
        where = f"{node.name()}: where {'; '.join(lower.reasons)} (codimension > 1)"
        try:
            with part(where, lower.describe, after=SLOW), time_budget(share):
                comps = lower.solve()
        except BudgetExceeded:
            if remaining_time() <= 0:  # the search's own budget: cut there
                raise
            self.cut.append((f"{where}: {lower.describe()}",
                             "a budget ran out" if share is None else
                             f"its share of the search's time, {share:.3g} s, ran out"))
            return
        self.clock.found(len(comps))
        self.visit(node, comps)

    def visit(self, node, comps) -> None:
        """Run the classification on each component (verified: its condition
        substituted), then follow the components found there."""
        keys = [(id(node), id(comps), k) for k in range(len(comps))]
        for key, comp in zip(keys, comps):
            self.pending[key] = tuple(node.conditions) + tuple(comp.equations)
        for key, comp in zip(keys, comps):
            self.clock.skip()  # this component is no longer pending (its runs are counted on)
            children = self.examine(node, comp, self.pending[key])
            del self.pending[key]  # examined: its verdicts are recorded
            for child in children:
                self.expand(*child)

    def examine(self, node, comp, full) -> list:
        """The verdicts on one component, recorded: [(node, data)] to follow."""
        why = _no_real_solution(comp.equations, self.signs)
        if why:
            self.dropped.append((full, why))
            return []
        out = []
        for branch in branches(comp.equations, tuple(node.system.declared_parameters),
                               self.signs):
            total = compose(node.sub, branch)
            why = _bad_substitution(total, self.signs)
            if why:
                self.dropped.append((full, why))
                continue
            key = canonical(total)
            if key in self.seen:
                continue
            self.seen.add(key)
            spec = rebuild(self.system, total, None)
            if isinstance(spec, Verdict):
                self.nodes.append((full, total, spec, node.verdict, comp.reasons))
                continue
            child = self.classify(spec, total, full, node, comp)
            if child is not None:
                out.append(child)
        return out

    def classify(self, spec, total, full, node, comp):
        """One case's verdict, recorded; (its node, its data) to follow, or None."""
        name = "run " + " and ".join(f"{short(e)} = 0" for e in full)
        with self.clock.run(name):
            try:
                verdict, data = classified(spec, **self.run)
            except InputError as exc:  # this case only (a secondary constraint in an
                # input): the other cases stand; BudgetExceeded is no InputError
                self.nodes.append((full, total, _not_classified(exc), node.verdict,
                                   comp.reasons))
                return None
            except BudgetExceeded:
                raise
            except Exception as exc:  # a failure of this run (the roller racer met a
                # RecursionError in one): the generic verdict and the other cases stand,
                # and the search is not complete
                self.failed.append((name, f"{type(exc).__name__}: {short(str(exc), 200)}"))
                return None
        self.nodes.append((full, total, verdict, node.verdict, comp.reasons))
        return _Node(spec, total, full, verdict, node.depth + 1), data


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
    forced = _force_parameters(system)
    names = sorted(p.name for p in held if p in forced)
    if not names or all(v.regular is not False for v in verdicts):
        return []
    return [f"C is singular in a verdict above, where the forces enter the secondary "
            f"constraints: the held {', '.join(names)} could change it there (keep "
            f"{'it' if len(names) == 1 else 'them'} symbolic: symbolic=, the command's "
            f"--symbolic)"]


def _force_parameters(system) -> set:
    """The parameters in the forces or the dissipation (those of a control law are not
    in the system's forces: inputs stand there, generic)."""
    forced = set(sp.sympify(system.dissipation).free_symbols)
    for f in system.forces:
        forced |= sp.sympify(f).free_symbols
    return {p for p in system.declared_parameters if p in forced}


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
    """Tells of each run: ``progress`` at its start, and on a terminal (a part, shown once
    the exploration has run :data:`~nhham.progress.SLOW` s) the runs done, their time, an
    estimate of what the runs known to be pending will take (more may appear below
    them) and the time left of the budget in force."""

    def __init__(self, progress):
        self.progress, self.runs, self.pending = progress, 0, 0
        self.begin = time.monotonic()

    def spent(self) -> float:
        return time.monotonic() - self.begin

    def note(self) -> str:
        spent = self.spent()
        note = f"{self.runs} run{'s' if self.runs != 1 else ''} done in {spent:.1f} s"
        if self.runs:  # this run and those pending, at the mean time of a run so far
            note += (f"; about {spent / self.runs * (self.pending + 1):.0f} s for this run "
                     f"and the {self.pending} more known")
        return note

    def shown(self) -> str:
        """The note as shown on a terminal (with the budget's time left)."""
        left = remaining_time()
        return self.note() + ("" if math.isinf(left) else f"; {left:.0f} s of the budget left")

    @contextmanager
    def run(self, what: str) -> Iterator[None]:
        if self.progress is not None:
            self.progress(what, self.note())
        with part(what, self.shown, after=max(0.0, SLOW - self.spent())):
            yield
        self.runs += 1

    def found(self, count: int) -> None:
        self.pending += count

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


