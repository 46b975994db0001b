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

A quantity is any object with a ``what`` (str) and some of the methods

``reduced(manifold, policy)``
    the answer by exact reduction, or None;
``value(env, degrees=False)``
    the datum at one point in the arithmetic of ``env`` (rationals, residues, or
    :class:`~nhham.lagrangian.domains.Degree` bounds with ``degrees``); raises
    ZeroDivisionError where a denominator vanishes (the point is drawn again);
``proved_modulo_p(value)``
    the answer a point over F_p proves, or None;
``observe(value)``
    records a rational point's value; True when the answer is decided (a proof);
``pending_error(degrees, count, bound)``
    the error bound of the verdicts still open after ``count`` points, None when none
    is (``bound``: the sampler's :class:`~nhham.lagrangian.domains.ErrorBound`, called
    with a numerator degree and the number of points);
``conclude(count, degrees, bound)``
    the answer from the points observed;
``residues``
    True when ``value``, ``observe`` and ``conclude`` also take residues modulo p:
    the quantity is then decided at smooth points over F_p of a curved M (step 3).
``sampled(manifold, policy)``
    the answer at floating-point points, or None.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from nhham.settings import SEED, check_options

__all__ = ["Policy", "decide", "policy_of", "answers_by_step", "proof_at_a_point"]


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


def decide(quantity, manifold, policy: Policy):
    """Answer ``quantity`` on ``manifold`` by the first step of the cascade that decides.

    Parameters
    ----------
    quantity
        A question on M (see the module docstring for the steps it may offer).
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


def _reduced(quantity, manifold, policy):
    reduced = getattr(quantity, "reduced", None)
    return None if reduced is None else reduced(manifold, policy)


def _sampled(quantity, manifold, policy):
    sampled = getattr(quantity, "sampled", None)
    return None if sampled is None else sampled(manifold, policy)


def proof_at_a_point(quantity, manifold, policy: Policy):
    """Step 2 alone: the answer a random point of M over F_p (the parameters at their
    values) proves, scoped to the component through it on a curved M; None when no
    point proves it. For the verdict at the parameter values, whose generic decisions
    a reduction took."""
    return _proof_modulo_p(quantity, manifold, policy)


def _proof_modulo_p(quantity, manifold, policy):
    """The answer a random point of M over F_p proves, else None."""
    # Looked up on the class: a property is evaluated only once M has exact points.
    if getattr(type(quantity), "proved_modulo_p", None) is None:
        return None
    from nhham.lagrangian.decision import scoped
    from nhham.lagrangian.domains import NotExact
    from nhham.lagrangian.points import exact_sampler

    try:
        sampler = exact_sampler(manifold, policy.seed, modular=True)
    except NotExact:
        return None
    proved = quantity.proved_modulo_p
    if proved is None or not _real(sampler, manifold, policy):
        return None
    for _ in range(policy.proof_tries):
        try:
            answer = proved(quantity.value(sampler.point().env))
        except (ZeroDivisionError, NotExact):
            continue
        if answer is not None:
            return scoped(answer, sampler.scope)
    return None


def _at_exact_points(quantity, manifold, policy):
    """The answer at random exact points of M with its error bound, else None (M has
    no exact points, or the datum is not exact there).

    Rational points where M has a rational parametrisation (the Schwartz–Zippel bound,
    points drawn until it is below ``policy.target_error``); on a curved M, for a
    quantity whose data may be residues (``residues = True``), ``policy.samples``
    smooth points over F_p (the Bézout bound of
    :class:`~nhham.lagrangian.domains.ErrorBound`, which more points do not lower).
    """
    if getattr(quantity, "observe", None) is None:
        return None
    from nhham.lagrangian.decision import scoped
    from nhham.lagrangian.domains import NotExact
    from nhham.lagrangian.points import REDRAWS

    try:
        sampler = _exact_points(quantity, manifold, policy)
        if sampler is None:
            return None
        count, degrees, bound, point = 0, None, None, None
        while count < policy.max_points:
            value = None
            for _ in range(1 + REDRAWS):
                point = sampler.point()
                try:
                    value = quantity.value(point.env)
                    break
                except ZeroDivisionError:
                    continue  # a denominator vanishes at this point: draw another
            if value is None:
                break
            count += 1
            if quantity.observe(value):
                break
            if degrees is None:
                degrees = quantity.value(point.degrees, degrees=True)
                bound = sampler.error_bound(point.degrees)
            error = quantity.pending_error(degrees, count, bound)
            if error is None or error < policy.target_error:
                break
            if bound.variety_degree and count >= policy.samples:
                break
        if count == 0:
            return None
        if bound is None:
            bound = sampler.error_bound(point.degrees)
        answer = quantity.conclude(count, degrees, bound)
        return scoped(answer, sampler.points_scope(count))
    except NotExact:
        return None


def _exact_points(quantity, manifold, policy):
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
    """The policy of a library call: ``policy`` itself, or one built from the call's
    keyword options (``precision``, ``samples``, ``seed``, ``tol``, ``exact``).

    Raises
    ------
    InputError
        When both are given and a keyword differs from its default (which would be
        silently ignored otherwise).
    """
    if policy is None:
        # Named after the caller, not the policy, when an option is out of range.
        check_options(where, **{k: v for k, v in options.items() if k != "exact"})
        return Policy(**options)
    if not isinstance(policy, Policy):
        from nhham.errors import InputError

        raise InputError(f"{where}: policy must be a nhham.Policy, got "
                         f"{type(policy).__name__}", key="policy")
    default = Policy()
    clash = [k for k, v in options.items() if v != getattr(default, k)]
    if clash:
        from nhham.errors import InputError

        raise InputError(f"{where}: {clash[0]} is given both as a keyword and in the policy; "
                         f"give it in the policy only", key=clash[0])
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
