"""The decision engine: one cascade decides every rank and vanishing on M_k.

``decide(quantity, manifold, policy)`` runs, in this order, the steps a quantity offers
and returns the first answer:

1. **exact reduction** (``quantity.reduced``): symbolic, where the policy's size
   thresholds say it is affordable;
2. **proof at an exact point** (``quantity.proved_modulo_p``): the datum at a random
   point of M over F_p, p = 2^61 − 1; a rank there is a lower bound of the generic
   rank over Q, so a full rank (or a nonzero value) is a proof; on a curved M
   (:mod:`nhham.lagrangian.curved`) the point is a smooth point and the proof holds on
   the component of M through it, which every Decision of the answer says
   (``Decision.scope``);
3. **exact points** (``quantity.observe`` / ``pending_error`` / ``conclude``): the
   datum at random rational points until the one Schwartz–Zippel bound
   (:func:`~nhham.lagrangian.domains.schwartz_zippel_bound`, degrees of numerator and
   denominator) of every verdict still open is below ``policy.target_error``; on a
   curved M, at ``policy.samples`` smooth points over F_p with the Bézout bound
   (:class:`~nhham.lagrangian.domains.ErrorBound`: the claim is then "on every
   component of M through the points");
4. **sampled points** (``quantity.sampled``): floating-point points of M found by
   Newton projection, with the evidence (singular values, residuals, warnings).

Steps 2 and 3 draw their points from the one exact sampler of M
(:func:`nhham.lagrangian.points.exact_sampler`) and are skipped with
``policy.exact = False``; a step that does not apply (no exact points: NotExact)
gives way to the next. The data of a quantity are the formulas of
:mod:`nhham.lagrangian.formulas`, evaluated in the arithmetic of the point.

A quantity is a :class:`Quantity` (a ``what``, str) offering some of the steps, each
declared by a :class:`typing.Protocol` of its own (a quantity lacking a step's members
skips that step; :func:`offers` tells which it has, looked up on the class):

:class:`Reduced`: ``reduced(manifold, policy)``
    the answer by exact reduction, or None;
:class:`ProvedModuloP`: ``value`` and ``proved_modulo_p(value)``
    ``value(env, degrees=False)`` is the datum at one point in the arithmetic of
    ``env`` (rationals, residues, or :class:`~nhham.lagrangian.domains.Degree` bounds
    with ``degrees``); it raises ZeroDivisionError where a denominator vanishes (the
    point is drawn again). ``proved_modulo_p`` gives the answer a point over F_p
    proves, or None (a property may give None for the whole step);
:class:`AtExactPoints`: ``value``, ``observe``, ``pending_error``, ``conclude``
    ``observe(value)`` records a rational point's value, True when the answer is
    decided (a proof); ``pending_error(degrees, count, bound)`` is the error bound of
    the verdicts still open after ``count`` points, None when none is (``bound``: the
    sampler's :class:`~nhham.lagrangian.domains.ErrorBound`, called with a numerator
    degree and the number of points); ``conclude(count, degrees, bound)`` is the
    answer from the points observed. A class attribute ``residues = True`` says that
    ``value``, ``observe`` and ``conclude`` also take residues modulo p: the quantity
    is then decided at smooth points over F_p of a curved M (step 3);
:class:`Sampled`: ``sampled(manifold, policy)``
    the answer at floating-point points, or None.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, cast

from nhham.settings import SEED, check_options

__all__ = ["Policy", "DEFAULT_POLICY", "decide", "policy_of", "answers_by_step",
           "proof_at_a_point", "Quantity", "Reduced", "ProvedModuloP", "AtExactPoints",
           "Sampled", "STEPS", "offers"]


@dataclass(frozen=True)
class Policy:
    """How decisions are made: arithmetic, sampling, thresholds and the time bound.

    One object, built once per command (or per library call) and passed down to every
    decision.

    Attributes
    ----------
    precision : int or None
        Sampled decisions in float64 (None) or mpmath with this many digits.
    samples, seed : int
        Number and seed of the sample points (exact and sampled).
    tol : float or None
        Relative tolerance of sampled decisions (None: 1e-9, or 10**(3 - digits)).
    exact : bool
        False: skip the exact steps (points over F_p and Q) and decide at sampled points.
    budget : float or None
        Seconds the command may take (``--budget``; None: no bound).
    target_error : float
        Exact points are drawn until every probabilistic verdict's Schwartz–Zippel
        bound is below this.
    max_points : int
        Most rational points per decision.
    proof_tries : int
        Points over F_p tried for a proof.
    closed_form_size : int
        Up to this many coordinates a decision is made symbolically first (the
        constraint algorithm's stage 1 and the Frobenius kernel basis).
    exact_minor_size : int
        Largest minor whose determinant a decision reduces exactly on M.
    combination_size : int
        Up to this many coordinates, first-class combinations decided at points are
        formed in closed form.
    symbolic_values_size : int
        Up to this n + m the verdict at the parameter values names its conditions
        with the parameters kept symbolic.

    Examples
    --------
    >>> from nhham import Policy, integrability, models
    >>> policy = Policy(samples=4, seed=7)
    >>> policy.precision is None, policy.samples, policy.seed
    (True, 4, 7)
    >>> integrability(models.rolling_disk(), policy=policy).integrable
    False
    """

    precision: int | None = None
    samples: int = 6
    seed: int = SEED
    tol: float | None = None
    exact: bool = True
    budget: float | None = None
    target_error: float = 1e-30
    max_points: int = 12
    proof_tries: int = 3
    closed_form_size: int = 4
    exact_minor_size: int = 6
    combination_size: int = 8
    symbolic_values_size: int = 10

    def __post_init__(self):
        check_options("Policy", precision=self.precision, samples=self.samples,
                      seed=self.seed, tol=self.tol)
        from nhham.errors import InputError

        if self.budget is not None and not (math.isfinite(self.budget) and self.budget > 0):
            raise InputError(f"Policy: budget must be a positive number of seconds, got "
                             f"{self.budget!r}", key="budget")
        if not 0 < self.target_error < 1:
            raise InputError(f"Policy: target_error must be in (0, 1), got "
                             f"{self.target_error!r}", key="target_error")
        for key in ("max_points", "proof_tries", "closed_form_size", "exact_minor_size",
                    "combination_size", "symbolic_values_size"):
            value = getattr(self, key)
            if not (isinstance(value, int) and not isinstance(value, bool) and value >= 0):
                raise InputError(f"Policy: {key} must be a whole number >= 0, got {value!r}",
                                 key=key)


#: The settings of a call that gives none.
DEFAULT_POLICY = Policy()


# ----------------------------------------------------------- the protocol
class Quantity(Protocol):
    """A question on M that :func:`decide` answers: what it asks, in words."""

    what: str


class Reduced(Quantity, Protocol):
    """Step 1: the answer by exact reduction on M, or None."""

    def reduced(self, manifold: Any, policy: Policy) -> Any: ...


class ProvedModuloP(Quantity, Protocol):
    """Step 2: the datum at a random point of M over F_p, and what it proves."""

    def value(self, env: Any, degrees: bool = False) -> Any: ...

    @property
    def proved_modulo_p(self) -> Callable[[Any], Any] | None: ...


class AtExactPoints(Quantity, Protocol):
    """Step 3: the data at random exact points until the error bound is met."""

    def value(self, env: Any, degrees: bool = False) -> Any: ...

    def observe(self, value: Any) -> bool: ...

    def pending_error(self, degrees: Any, count: int, bound: Any) -> float | None: ...

    def conclude(self, count: int, degrees: Any, bound: Any) -> Any: ...


class Sampled(Quantity, Protocol):
    """Step 4: the answer at floating-point points of M."""

    def sampled(self, manifold: Any, policy: Policy) -> Any: ...


#: The members each step's protocol asks of a quantity.
STEPS: dict[type, tuple[str, ...]] = {
    Reduced: ("reduced",),
    ProvedModuloP: ("value", "proved_modulo_p"),
    AtExactPoints: ("value", "observe", "pending_error", "conclude"),
    Sampled: ("sampled",),
}


def offers(quantity: Quantity, step: type) -> bool:
    """Whether ``quantity`` has every member of ``step`` (one of :data:`STEPS`).

    Looked up on the class: a property (``proved_modulo_p``) is evaluated only when the
    step runs.
    """
    cls = type(quantity)
    return all(getattr(cls, name, None) is not None for name in STEPS[step])


# ------------------------------------------------------------- the cascade
def decide(quantity: Quantity, manifold, policy: Policy):
    """Answer ``quantity`` on ``manifold`` by the first step of the cascade that decides.

    Parameters
    ----------
    quantity : Quantity
        A question on M, offering some of the steps (see the module docstring).
    manifold : Submanifold
        M, the zero set of the constraints the question is asked on.
    policy : Policy

    Returns
    -------
    object or None
        The quantity's answer (a :class:`~nhham.lagrangian.decision.Decision` or a
        result made of Decisions); None when no step applies (the caller then has a
        route of its own, e.g. the symbolic constraint algorithm).
    """
    steps = [_reduced]
    if policy.exact:
        steps += [_proof_modulo_p, _at_exact_points]
    steps.append(_sampled)
    for step in steps:
        answer = step(quantity, manifold, policy)
        if answer is not None:
            return answer
    return None


def _reduced(quantity: Quantity, manifold, policy):
    if not offers(quantity, Reduced):
        return None
    return cast(Reduced, quantity).reduced(manifold, policy)


def _sampled(quantity: Quantity, manifold, policy):
    if not offers(quantity, Sampled):
        return None
    return cast(Sampled, quantity).sampled(manifold, policy)


def proof_at_a_point(quantity: Quantity, manifold, policy: Policy):
    """Step 2 alone: the answer a random point of M over F_p (the parameters at their
    values) proves, scoped to the component through it on a curved M; None when no
    point proves it. For the verdict at the parameter values, whose generic decisions
    a reduction took."""
    return _proof_modulo_p(quantity, manifold, policy)


def _proof_modulo_p(quantity: Quantity, manifold, policy):
    """The answer a random point of M over F_p proves, else None."""
    # Looked up on the class (offers): a property is evaluated only once M has exact
    # points.
    if not offers(quantity, ProvedModuloP):
        return None
    q = cast(ProvedModuloP, quantity)
    from nhham.lagrangian.decision import scoped
    from nhham.lagrangian.domains import NotExact
    from nhham.lagrangian.points import exact_sampler

    try:
        sampler = exact_sampler(manifold, policy.seed, modular=True)
    except NotExact:
        return None
    proved = q.proved_modulo_p
    if proved is None or not _real(sampler, manifold, policy):
        return None
    for _ in range(policy.proof_tries):
        try:
            answer = proved(q.value(sampler.point().env))
        except (ZeroDivisionError, NotExact):
            continue
        if answer is not None:
            return scoped(answer, sampler.scope)
    return None


def _at_exact_points(quantity: Quantity, manifold, policy):
    """The answer at random exact points of M with its error bound, else None (M has
    no exact points, or the datum is not exact there).

    Rational points where M has a rational parametrisation (the Schwartz–Zippel bound,
    points drawn until it is below ``policy.target_error``); on a curved M, for a
    quantity whose data may be residues (``residues = True``), ``policy.samples``
    smooth points over F_p (the Bézout bound of
    :class:`~nhham.lagrangian.domains.ErrorBound`, which more points do not lower).
    """
    if not offers(quantity, AtExactPoints):
        return None
    q = cast(AtExactPoints, quantity)
    from nhham.lagrangian.decision import scoped
    from nhham.lagrangian.domains import NotExact
    from nhham.lagrangian.points import REDRAWS

    try:
        sampler = _exact_points(quantity, manifold, policy)
        if sampler is None:
            return None
        count, degrees = 0, None
        bound: Any = None
        point: Any = None
        while count < policy.max_points:
            value = None
            for _ in range(1 + REDRAWS):
                point = sampler.point()
                try:
                    value = q.value(point.env)
                    break
                except ZeroDivisionError:
                    continue  # a denominator vanishes at this point: draw another
            if value is None:
                break
            count += 1
            if q.observe(value):
                break
            if degrees is None:
                degrees = q.value(point.degrees, degrees=True)
                bound = sampler.error_bound(point.degrees)
            error = q.pending_error(degrees, count, bound)
            if error is None or error < policy.target_error:
                break
            if bound.variety_degree and count >= policy.samples:
                break
        if count == 0:
            return None
        if bound is None:
            bound = sampler.error_bound(point.degrees)
        answer = q.conclude(count, degrees, bound)
        return scoped(answer, sampler.points_scope(count))
    except NotExact:
        return None


def _exact_points(quantity: Quantity, manifold, policy):
    """The sampler of the exact points of M: rational, or over F_p on a curved M for a
    quantity that takes residues; None when neither applies."""
    from nhham.lagrangian.domains import NotExact
    from nhham.lagrangian.points import exact_sampler

    try:
        return exact_sampler(manifold, policy.seed)
    except NotExact:
        if not getattr(quantity, "residues", False):
            return None
    sampler = exact_sampler(manifold, policy.seed, modular=True)
    if sampler.chart is None or not _real(sampler, manifold, policy):
        return None
    return sampler


def _real(sampler, manifold, policy) -> bool:
    """Points over F_p of a curved M speak of M only where M has real points."""
    return sampler.chart is None or manifold.has_real_point(sampler.chart.constraints,
                                                            policy)


def policy_of(policy: Policy | None, where: str, **options) -> Policy:
    """The policy of a library call: ``policy`` itself, or, from the deprecated keyword
    options, one built from them.

    A :class:`Policy` is the one way to pass decision settings to a public function
    (``policy=Policy(samples=3)``). The loose keywords ``precision``, ``samples``,
    ``seed``, ``tol`` and ``exact`` that eleven functions took before are kept for one
    release: one that differs from its default raises a ``DeprecationWarning`` naming the
    replacement, and is used.

    Parameters
    ----------
    policy : Policy or None
    where : str
        The public function, named in messages.
    **options
        The function's loose keywords as given (their defaults are Policy's).

    Raises
    ------
    InputError
        When both are given and a keyword differs from its default (which would be
        silently ignored otherwise), or ``policy`` is not a Policy.

    Examples
    --------
    >>> import warnings
    >>> policy_of(Policy(samples=3), "f").samples
    3
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     policy_of(None, "f", samples=3, seed=Policy().seed).samples
    3
    >>> print(caught[0].category.__name__, caught[0].message)
    DeprecationWarning f: samples= is deprecated; pass policy=nhham.Policy(samples=3) instead
    """
    given = {k: v for k, v in options.items() if v != getattr(DEFAULT_POLICY, k)}
    if policy is None:
        if given:
            import warnings

            settings = ", ".join(f"{k}={v!r}" for k, v in given.items())
            warnings.warn(f"{where}: {'= and '.join(given)}= "
                          f"{'is' if len(given) == 1 else 'are'} deprecated; pass "
                          f"policy=nhham.Policy({settings}) instead", DeprecationWarning,
                          stacklevel=3)
        # Named after the caller, not the policy, when an option is out of range.
        check_options(where, **{k: v for k, v in options.items() if k != "exact"})
        return Policy(**options)
    if not isinstance(policy, Policy):
        from nhham.errors import InputError

        raise InputError(f"{where}: policy must be a nhham.Policy, got "
                         f"{type(policy).__name__}", key="policy")
    if given:
        from nhham.errors import InputError

        clash = next(iter(given))
        raise InputError(f"{where}: {clash} is given both as a keyword and in the policy; "
                         f"give it in the policy only", key=clash)
    return policy


def answers_by_step(quantity_factory, manifold, policy: Policy) -> dict:
    """Every step's answer to the same question, each from a fresh quantity:
    ``{"reduced" | "proof modulo p" | "exact points" | "sampled": answer}`` for the
    steps that answer.

    The steps evaluate the same formulas in different arithmetics (sympy, GF(p), QQ
    with degree bounds, float64/mpmath), so answers that disagree expose a defect in
    one of them; the tests of the engine compare them.
    """
    steps = {"reduced": _reduced, "proof modulo p": _proof_modulo_p,
             "exact points": _at_exact_points, "sampled": _sampled}
    out = {}
    for name, step in steps.items():
        answer = step(quantity_factory(), manifold, policy)
        if answer is not None:
            out[name] = answer
    return out
