"""``method="auto"``: a method chosen from what the scene is, with the reason.

The facts are read from the numeric model and the run's request, nothing symbolic is
derived for them: whether the system is *mechanical* (L = 1/2 v^T W(q) v + b(q) . v - V(q),
no applied forces or inputs, t nowhere, constraints affine in v), whether it is
*reversible* (mechanical, b = 0 and the constraints linear: L, the constraints and the
field are unchanged by v -> -v), and from the spectrum of the field's Jacobian at the
initial state (central differences, 4n evaluations) its fastest rate rho = max |lambda|,
its fastest decay sigma = max(-Re lambda) and how many radians of the fastest motion the
horizon holds (``periods`` = rho T / (2 pi)).

The decision table (:data:`RULES`, the first that holds):

================ ========================================== ===================
rule             when                                       method
================ ========================================== ===================
stiff            sigma T > 1e4 and sigma > 1e3 x the largest Radau
                 rate of the modes that decay slower (1e-3
                 sigma): a fast transient beside a slow motion
not mechanical   forces, inputs, t, Chetaev's constraints,   DOP853
                 L not of the mechanical form
short horizon    fewer than 100 periods of the fastest       DOP853
                 motion
hamiltonizable   long horizon, a scene whose reduction has   hamiltonized
                 a conformal factor (tried within 20 s)
reversible       long horizon, reversible                    rattle
mechanical       long horizon, not reversible (a gyroscopic  discrete_gradient
                 term or affine constraints)
================ ========================================== ===================

Why: an adaptive high-order method is the most accurate at a given cost over a few periods
and is the only one that takes forces, t and Chetaev's rule (the energy balance is then
what the run reports); over long horizons what a method preserves decides
(``bench/long_horizon.py``): on reversible problems RATTLE's energy error stays bounded
at the lowest cost a step, and where the system is not reversible the energy-exact
discrete gradient keeps the energy (or, with affine constraints, its balance with the
reactions' work) to rounding. A fixed-step method takes the step 0.05/rho (about 125 steps
a period of the fastest motion) unless one is given. With ``step`` given the choice is among
the fixed-step methods (rk4 where neither structure-preserving one applies), with ``rtol``,
``atol``, ``t_eval``, ``dense_output``, ``events``, ``projection`` or ``baumgarte`` among
the adaptive ones.

Examples
--------
>>> import nhham
>>> from nhham.numerics.method_choice import choose_method
>>> spring = nhham.numeric_model(nhham.System(["x"], "x_dot**2/2 - x**2/2"),
...                              backend="numpy")
>>> choose_method(spring, [1.0, 0.0], (0.0, 10.0)).method
'DOP853'
>>> long = choose_method(spring, [1.0, 0.0], (0.0, 1e4))
>>> long.method, long.options
('rattle', {'step': 0.05})
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from nhham.numerics.methods import METHODS

__all__ = ["Facts", "MethodChoice", "RULES", "choose_method", "choice_for", "scene_facts"]

#: Horizons of at least this many periods of the fastest motion are long.
LONG_PERIODS = 100.0
#: Steps a radian of the fastest motion for the fixed-step choices (h = STEP_FRACTION/rho).
STEP_FRACTION = 0.05
#: The longest ``auto`` waits for a Hamiltonization (symbolic) before it goes on without.
HAMILTONIZE_SECONDS = 20.0


def _try(reducer) -> tuple:
    """(field, "") or (None, why): the reducer within HAMILTONIZE_SECONDS."""
    from nhham.budget import time_budget
    from nhham.errors import BudgetExceeded, NhhamError

    try:
        with time_budget(HAMILTONIZE_SECONDS):
            return reducer(), ""
    except BudgetExceeded:
        return None, f"not decided within {HAMILTONIZE_SECONDS:g} s"
    except NhhamError as exc:
        return None, str(exc).split(": ", 1)[-1]


@dataclass(frozen=True)
class Facts:
    """What the decision reads (see the module docstring)."""

    mechanical: bool
    reversible: bool
    why_not_mechanical: str
    rho: float
    sigma: float
    stiffness: float
    periods: float
    horizon: float
    hamiltonizable: bool | None = None
    why_not_hamiltonizable: str = ""

    @property
    def stiff(self) -> bool:
        return self.sigma * self.horizon > 1e4 and self.stiffness > 1e3

    def to_dict(self) -> dict:
        return {"mechanical": self.mechanical, "reversible": self.reversible,
                "not_mechanical_because": self.why_not_mechanical or None,
                "fastest_rate": self.rho, "fastest_decay": self.sigma + 0.0,
                "stiffness_ratio": self.stiffness, "periods": self.periods,
                "stiff": self.stiff, "hamiltonizable": self.hamiltonizable,
                "not_hamiltonizable_because": self.why_not_hamiltonizable or None}


@dataclass(frozen=True)
class Rule:
    """One row of the decision table; its method is the registry's entry whose
    ``auto_for`` names the rule (:data:`nhham.numerics.methods.METHODS`)."""

    name: str
    holds: Callable[[Facts], bool]
    reason: Callable[[Facts], str]

    @property
    def method(self) -> str:
        return picked_by(self.name)


def picked_by(rule: str) -> str:
    """The one method of the registry that ``rule`` chooses."""
    found = [m.name for m in METHODS.values() if rule in m.auto_for]
    assert len(found) == 1, (rule, found)   # the registry is data the table trusts
    return found[0]


RULES = (
    Rule("stiff", lambda f: f.stiff,
         lambda f: f"stiff: a decay rate {f.sigma:.3g} is {f.stiffness:.3g} times the rates of "
                   f"the slow motion, over {f.sigma * f.horizon:.3g} of its time constants"),
    Rule("not mechanical", lambda f: not f.mechanical,
         lambda f: f"{f.why_not_mechanical}: an adaptive method, the energy balance reported"),
    Rule("short horizon", lambda f: f.periods < LONG_PERIODS,
         lambda f: f"a short horizon ({f.periods:.3g} periods of the fastest motion): the most "
                   f"accurate at its cost"),
    Rule("hamiltonizable", lambda f: f.periods >= LONG_PERIODS and bool(f.hamiltonizable),
         lambda f: f"a long horizon ({f.periods:.3g} periods) on a Hamiltonizable reduction: "
                   f"a symplectic method in Chaplygin's time keeps the energy bounded"),
    Rule("reversible", lambda f: f.periods >= LONG_PERIODS and f.reversible,
         lambda f: f"a long horizon ({f.periods:.3g} periods) on a reversible system: "
                   f"RATTLE keeps the energy error bounded at the least cost a step"),
    Rule("mechanical", lambda f: f.mechanical and f.periods >= LONG_PERIODS,
         lambda f: f"a long horizon ({f.periods:.3g} periods) on a system that is not "
                   f"reversible: the discrete gradient keeps the energy (its balance) exactly"),
)


@dataclass(frozen=True)
class MethodChoice:
    """The method ``auto`` chose, the options it set, and why."""

    method: str
    options: dict = field(default_factory=dict)
    rule: str = ""
    reason: str = ""
    facts: Facts | None = None

    def describe(self) -> str:
        step = f" with step {self.options['step']:.3g}" if "step" in self.options else ""
        return f"method auto: {self.method}{step}, {self.reason}"

    def to_dict(self) -> dict:
        options = {k: (v.factor_text if k == "reduced" else v) for k, v in self.options.items()}
        return {"method": self.method, "options": options, "rule": self.rule,
                "reason": self.reason,
                "facts": None if self.facts is None else self.facts.to_dict()}


def _not_mechanical(model) -> str:
    """Why L, the forces or the constraints are not of the mechanical form ("" if they are)."""
    if model.forced:
        return "applied forces"
    if model.input_names:
        return "inputs"
    if model.time_in_geometry or model.time_slot is not None:
        return "t in the scene"
    if model.nonlinear:
        return "a constraint nonlinear in the velocities"
    if not (model.quadratic or model.layout.get("linear_terms")):
        return "L is not 1/2 v^T W(q) v + b(q) . v - V(q)"
    return ""


def _spectrum(model, y0) -> np.ndarray:
    """Eigenvalues of the field's Jacobian at y0 (central differences); none where the
    field is not defined there (the run then says why)."""
    from nhham.numerics.status import NumericalFailure

    y0 = np.asarray(y0, dtype=float)
    d = y0.size
    J = np.empty((d, d))
    try:
        for j in range(d):
            e = 1e-6 * max(1.0, abs(y0[j]))
            up, down = y0.copy(), y0.copy()
            up[j] += e
            down[j] -= e
            J[:, j] = (model.rhs(0.0, up) - model.rhs(0.0, down)) / (2 * e)
    except (NumericalFailure, ArithmeticError, np.linalg.LinAlgError):
        return np.zeros(0)
    if not np.all(np.isfinite(J)):
        return np.zeros(0)
    return np.linalg.eigvals(J)


def scene_facts(model, y0, t_span) -> Facts:
    """The :class:`Facts` of a run of ``model`` from ``y0`` over ``t_span``."""
    horizon = abs(float(t_span[1]) - float(t_span[0]))
    why = _not_mechanical(model)
    reversible = not why and model.quadratic and model.linear_constraints
    lam = _spectrum(model, y0)
    rho = float(np.max(np.abs(lam))) if lam.size else 0.0
    sigma = float(max(np.max(-lam.real), 0.0)) if lam.size else 0.0
    # the rates of the motion beside the fast decay (none: the decay is the motion itself)
    slow = max((abs(x) for x in lam if -x.real <= 1e-3 * sigma), default=0.0)
    return Facts(mechanical=not why, reversible=bool(reversible), why_not_mechanical=why,
                 rho=rho, sigma=sigma, stiffness=sigma / slow if slow > 0 else 0.0,
                 periods=rho * horizon / (2 * math.pi), horizon=horizon)


def choose_method(model, y0, t_span, given=(), reducer=None) -> MethodChoice:
    """The method of ``method="auto"`` for a run of ``model`` from ``y0`` (2n,) over
    ``t_span``, by :data:`RULES`; ``given``: the options the user set (``step`` keeps the
    choice among the fixed-step methods, ``rtol``/``atol`` among the adaptive ones);
    ``reducer``: a callable giving the scene's Hamiltonized field (or raising NhhamError
    with the obstruction), tried within :data:`HAMILTONIZE_SECONDS` for a long run of a
    mechanical system only."""
    facts = scene_facts(model, y0, t_span)
    given = set(given)
    # output at given times, dense output, events and projection are the adaptive
    # methods' (the structure-preserving ones keep their grid and their constraints)
    family = ("fixed-step" if "step" in given else
              "adaptive" if given & {"rtol", "atol", "max_step", "first_step", "t_eval",
                                     "dense_output", "events", "projection",
                                     "baumgarte"} else None)
    field = None
    if (reducer is not None and facts.mechanical and facts.periods >= LONG_PERIODS
            and family != "adaptive"):
        field, why = _try(reducer)
        facts = replace(facts, hamiltonizable=field is not None, why_not_hamiltonizable=why)
    for rule in RULES:
        if rule.holds(facts) and family in (None, METHODS[rule.method].family):
            chosen = _with_step(rule.method, rule.name, rule.reason(facts), facts, given)
            if METHODS[rule.method].needs_reduction:
                chosen.options["reduced"] = field
            return chosen
    if family == "fixed-step":   # forces, t, Chetaev, or a short horizon with a step given
        why = (facts.why_not_mechanical or f"a short horizon ({facts.periods:.3g} periods of "
               f"the fastest motion)")
        return _with_step(picked_by("fixed step given"), "fixed step given",
                          f"{why} and a step given: the classical Runge-Kutta 4, the most "
                          f"accurate fixed-step method that applies", facts, given)
    return MethodChoice(picked_by("tolerances given"), {}, "tolerances given",
                        "tolerances were given: an adaptive method", facts)


def _with_step(method, rule, reason, facts, given) -> MethodChoice:
    options = {}
    if METHODS[method].fixed_step and "step" not in given:
        rate = facts.rho if facts.rho > 0 else 1.0 / max(facts.horizon, 1e-300)
        options["step"] = float(f"{min(STEP_FRACTION / rate, facts.horizon / 100):.3g}")
    return MethodChoice(method, options, rule, reason, facts)



def choice_for(system_or_model, t_span, y0, options=None, method_options=None,
               keywords=None) -> MethodChoice:
    """:func:`choose_method` for the arguments of :func:`nhham.numerics.integrate.simulate`
    with ``method="auto"`` (a System is made numeric as simulate makes it; the options
    given, by keyword or as a family's options, keep the choice in their family)."""
    from nhham.numerics.model import NumericModel
    from nhham.numerics.simulate_options import FixedStepOptions

    keywords = dict(keywords or {})
    reducer = keywords.get("reduced", getattr(options, "reduced", None))
    # what was asked (projection=False or events=None ask for nothing)
    given = {k for k, v in keywords.items() if v is not None and v is not False} - {"reduced"}
    if isinstance(method_options, FixedStepOptions):
        given.add("step")
    elif method_options is not None:
        given.add("rtol")
    model, state = system_or_model, y0
    if not isinstance(model, NumericModel):
        from nhham.numerics.codegen import numeric_model, system_and_state

        if hasattr(y0, "keys"):
            model, state = system_and_state(model, y0)
        backend = keywords.get("backend", getattr(options, "backend", None) or "auto")
        model = numeric_model(model, backend=backend, background=True)
    return choose_method(model, model.state(state), t_span, given,
                         reducer=reducer if callable(reducer) else None)
