"""The Dirac–Bergmann chain of a singular Lagrangian, and what it says on the final surface.

Conventions (``DESIGN.md`` §2, "Singular Lagrangians"): the primary constraints phi_a and
H_c come from :mod:`nhham.hamiltonian.primary`; the chain is the paper's constraint
algorithm (:func:`nhham.lagrangian.algorithm.run_algorithm`) on T*Q with base field
X_{H_c} and one field per multiplier, X_{phi_a} (``u_<a>``) and X_g for the scene's
holonomic g (``lambda_<i>``), X_f(chi) = {chi, f}:

    0 = {chi, H_c} + u^a {chi, phi_a} + lambda^i {chi, g_i}      on M_k,

every "vanishes on M_k" and every rank decided by the decision engine (``Submanifold``
of T*Q, recorded). On the final surface M_f:

* B_ab = {chi_a, chi_b}; rank B = the number of second-class constraints (the rank, never
  a zero-row rule); the independent constraints number rho = 2n - dim M_f (a reducible
  set such as x, p, x p counts 2); first class = rho - rank B;
* irregular constraints (gradient zero on M_f) are named, and the degrees of freedom
  (2n - 2 FC - SC) / 2 are stated only when there is none;
* gauge generators by Castellani's chain from each primary first-class combination;
* the Dirac bracket of the phase coordinates over a maximal second-class set.

The verdict is at the scene's parameter values: they are put in exactly (as rationals)
before anything is derived; parameters without a value stay symbolic.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from functools import cached_property
from typing import TYPE_CHECKING, cast

import sympy as sp

from nhham.errors import InputError
from nhham.hamiltonian.brackets import BracketAlgebra, DiracBracket
from nhham.hamiltonian.classes import ConstraintClasses
from nhham.hamiltonian.classification import classify_on
from nhham.hamiltonian.primary import LegendreImage, legendre_image
from nhham.lagrangian.algebra import cancel
from nhham.lagrangian.decision import Decision
from nhham.lagrangian.engine import Policy
from nhham.lagrangian.records import AlgorithmRun
from nhham.lagrangian.submanifold import Submanifold
from nhham.system.naming import (gauge_parameter_symbol, multiplier_symbol,
                                 primary_multiplier_symbol)

if TYPE_CHECKING:
    from nhham.system.description import System

__all__ = ["DiracBergmann", "GaugeGenerator", "dirac_bergmann", "at_parameter_values",
           "with_parameters"]


@dataclass(frozen=True)
class GaugeGenerator:
    """G = sum_k eps^(k) G_k, generating delta z = {z, G} (Castellani).

    Attributes
    ----------
    index : int
        a of the gauge parameter eps_a (its k-th time derivative
        :func:`~nhham.system.naming.gauge_parameter_symbol` (a, k)).
    terms : tuple of (int, sympy.Expr)
        (k, G_k), highest derivative first; G_K is a primary first-class combination.
    transformations : tuple of (sympy.Symbol, sympy.Expr)
        (z, delta z) for every phase coordinate with a nonzero delta z.
    checked : Decision
        Every G_k first class on M_f (its brackets with every final constraint vanish).
    """

    index: int
    terms: tuple
    transformations: tuple
    checked: Decision

    @property
    def parameter(self) -> sp.Symbol:
        """eps_a."""
        return gauge_parameter_symbol(self.index)

    @property
    def expression(self) -> sp.Expr:
        """sum_k eps^(k) G_k, the derivatives written ``eps_dot``, ``eps_ddot``, ..."""
        return sum((gauge_parameter_symbol(self.index, k) * g for k, g in self.terms), sp.S.Zero)


@dataclass(frozen=True, eq=False)
class DiracBergmann:
    """The Dirac–Bergmann chain of a singular Lagrangian and its final surface (frozen).

    Attributes
    ----------
    system : nhham.System
        The system at the scene's parameter values (what the chain was run on).
    image : LegendreImage
        Primary constraints and H_c.
    run : AlgorithmRun
        The chain: stages (generations), final constraints, determined and free
        multipliers, the decisions.
    multipliers : tuple of sympy.Symbol
        The multipliers of the holonomic g (``lambda_<i>``) then of the primaries (``u_<a>``).
    base_field, vertical_fields : sympy.Matrix
        X_{H_c} (2n x 1) and one row per multiplier: X_g, -mu_i d/dp for a velocity
        constraint (its reaction), X_{phi_a}.
    functions : tuple of sympy.Expr or None
        What each multiplier multiplies in H_T (None for a velocity constraint's: its
        reaction is no Hamiltonian field).
    conditions : tuple of (str, sympy.Expr)
        The velocity constraints phi_i(q, v) at v = dH_T/dp (affine in the u^a): conditions
        on the motion (``run_algorithm``'s ``field_conditions``).
    replaced : tuple of (str, sympy.Expr, sympy.Expr)
        (label, given, regular equivalent) for each holonomic constraint given as an
        irregular equation (x**2: its gradient vanishes where it holds), replaced by one
        with the same zero set and a nonzero gradient (x) before the chain ran.
    gauge : tuple of sympy.Expr
        Gauge conditions chi(q) = 0 (``gauge[i]``) that joined M_1 to fix the free
        multipliers (no multiplier of their own); () for the chain of the Lagrangian alone.
    velocities_as_state : tuple of sympy.Symbol
        The u^a when they are state variables, not multipliers: a velocity constraint or a
        force nonlinear in the velocities along ker W (``DESIGN.md`` §2); the chain then
        runs on T*Q x R^r with the u_a' (``u_<a>_dot``) as multipliers. () otherwise.

    Examples
    --------
    L = (q1' - q2)^2/2: p_q2 -> p_q1, both first class, no degree of freedom, and the
    gauge symmetry delta q1 = eps, delta q2 = eps_dot.

    >>> from nhham import System
    >>> from nhham.hamiltonian.dirac_bergmann import dirac_bergmann
    >>> db = dirac_bergmann(System(["q1", "q2"], "(q1_dot - q2)**2/2"))
    >>> db.generations
    ((p_q2,), (-p_q1,))
    >>> db.first_class, db.second_class, db.degrees_of_freedom
    (2, 0, 0)
    >>> db.gauge_generators[0].transformations
    ((q1, eps_1), (q2, eps_1_dot))
    """

    system: "System"
    image: LegendreImage
    run: AlgorithmRun
    multipliers: tuple
    base_field: sp.Matrix
    vertical_fields: sp.Matrix
    policy: Policy
    replaced: tuple = ()
    functions: tuple = ()
    conditions: tuple = ()
    gauge: tuple = ()
    velocities_as_state: tuple = ()

    # ------------------------------------------------------------------ chain
    @property
    def status(self) -> str:
        return self.run.status

    @property
    def consistent(self) -> bool:
        return self.run.status != "inconsistent"

    @property
    def n(self) -> int:
        return self.system.n

    @cached_property
    def algebra(self) -> BracketAlgebra:
        return BracketAlgebra(self.image.coordinates, self.image.momenta)

    @property
    def variables(self) -> tuple:
        """The chain's state: (q, p), and the u^a where they are state variables."""
        return tuple(self.algebra.variables) + tuple(self.velocities_as_state)

    @property
    def phase_constraints(self) -> tuple:
        """(labels, constraints) of M_f free of the u^a: the constraints on T*Q, which the
        classes are about (those with u fix the velocities along ker W)."""
        u = set(self.velocities_as_state)
        pairs = [(lab, c) for lab, c in zip(self.run.final_labels, self.run.final_constraints)
                 if not (sp.sympify(c).free_symbols & u)]
        return tuple(lab for lab, _ in pairs), tuple(c for _, c in pairs)

    @property
    def generation_labels(self) -> tuple:
        """Labels of the constraints generation by generation (primary first)."""
        stages = self.run.stages
        if not stages:
            return (tuple(self.run.final_labels),)
        out = [tuple(stages[0].labels)]
        out += [tuple(s.new_labels) for s in stages if s.new_labels]
        return tuple(out)

    @property
    def generations(self) -> tuple:
        """The constraints in (q, p), generation by generation (primary first)."""
        named = self.named_constraints
        return tuple(tuple(named[lab] for lab in gen) for gen in self.generation_labels)

    @cached_property
    def named_constraints(self) -> dict:
        """{label: constraint in (q, p)} of every constraint the chain met."""
        out: dict = {}
        for s in self.run.stages:
            out.update(zip(s.labels, s.constraints))
            out.update(zip(s.new_labels, s.new_constraints))
        out.update(zip(self.run.final_labels, self.run.final_constraints))
        return out

    @property
    def manifold(self) -> Submanifold:
        """M_f in T*Q (the chain must be consistent)."""
        if not self.consistent or self.run.manifold is None:
            raise InputError(f"the chain is inconsistent: {self.run.inconsistency}")
        return self.run.manifold

    # --------------------------------------------------------------- classes
    @cached_property
    def classes(self) -> ConstraintClasses | None:
        """B_ab = {chi_a, chi_b} on M_f, its rank, R and the first-class combinations."""
        if not self.consistent:
            return None
        labels, constraints = self.phase_constraints
        return classify_on(self.manifold, self.algebra, constraints, labels,
                           tol=self.policy.tol)

    @property
    def independent(self) -> int | None:
        """rho = 2n - dim M_f, the number of independent constraints (with the u^a as
        state: the rank of the phase constraints' Jacobian in (q, p) on M_f)."""
        if not self.consistent or self.run.dimension is None:
            return None
        if self.velocities_as_state:
            _, constraints = self.phase_constraints
            if not constraints:
                return 0
            J = sp.Matrix(list(constraints)).jacobian(list(self.algebra.variables))
            return int(cast(int, self.manifold.rank(J, tol=self.policy.tol).value))
        return 2 * self.n - int(self.run.dimension)

    @property
    def second_class(self) -> int | None:
        return None if self.classes is None else int(self.classes.rank)

    @property
    def first_class(self) -> int | None:
        if self.classes is None or self.independent is None:
            return None
        return self.independent - int(self.classes.rank)

    @cached_property
    def irregular_decisions(self) -> dict:
        """{label: Decision that the gradient of chi vanishes on M_f} for every chi."""
        if not self.consistent:
            return {}
        M = self.manifold
        z = self.algebra.variables
        out: dict = {}
        for lab, chi in zip(*self.phase_constraints):
            worst = None
            for s in z:
                d = M.vanishes(cancel(sp.diff(chi, s)), tol=self.policy.tol)
                if not d.value:
                    worst = d
                    break
                worst = d if worst is None or d.method == "sampled" else worst
            out[lab] = worst
        return out

    @property
    def irregular(self) -> tuple:
        """Labels of the final constraints whose gradient vanishes on M_f (z^2, p^2) that
        no regular equivalent replaced."""
        return tuple(lab for lab, d in self.irregular_decisions.items() if d.value)

    @property
    def degrees_of_freedom(self):
        """(2n - 2 FC - SC) / 2 (an int, or a Fraction when it is not whole), or None when
        the chain is inconsistent or a constraint is irregular (the count would be wrong).
        A constraint replaced by its regular equivalent (``replaced``) is counted as that."""
        if (self.first_class is None or self.irregular or self.conditions
                or self.velocities_as_state):
            return None  # velocity constraints restrict the motion, not T*Q: no such count
        dof = Fraction(2 * self.n - 2 * self.first_class - self.second_class, 2)
        return int(dof) if dof.denominator == 1 else dof

    # ------------------------------------------------------------- the motion
    @property
    def fixed_multipliers(self) -> dict:
        """{multiplier: expression} of those the chain determined on M_f (the free ones
        appear in them as symbols)."""
        return dict(self.run.multipliers) if self.consistent else {}

    @cached_property
    def motion(self) -> sp.Matrix:
        """z' on M_f: X_{H_c} + lambda^i Z_i with the multipliers the chain fixed put in
        (the free ones as symbols), shape (2n, 1)."""
        lam = sp.Matrix(self.multipliers).xreplace(self.fixed_multipliers)
        return (self.base_field + self.vertical_fields.T * lam).applyfunc(cancel)

    @cached_property
    def hamiltonian(self) -> sp.Expr:
        """H' = H_c + the determined multipliers times their constraints (free ones 0)."""
        lam = self.fixed_multipliers
        free = {s: 0 for s in self.run.free_multiplier_symbols}
        H = self.image.canonical_hamiltonian
        for sym, chi in zip(self.multipliers, self.functions):
            if sym in lam and chi is not None:
                H += sp.sympify(lam[sym]).xreplace(free) * chi
        return cancel(H)

    @property
    def total_hamiltonian(self) -> sp.Expr:
        """H_T = H_c + u^a phi_a (+ lambda^i g_i), every multiplier a symbol (a velocity
        constraint's reaction is not in it: no Hamiltonian field)."""
        H = self.image.canonical_hamiltonian + sum(
            (s * c for s, c in zip(self.multipliers, self.functions) if c is not None),
            sp.S.Zero)
        # u^a as state: their primaries' terms are not multiplied by a multiplier
        return H + sum((u * phi for u, phi in zip(self.velocities_as_state,
                                                   self.image.constraints)), sp.S.Zero)

    @cached_property
    def primary_first_class(self) -> tuple:
        """A basis of the first-class combinations of the primary constraints (expressions
        in (q, p)): the kernel of (B_ab) restricted to the primary columns, on M_f."""
        if not self.consistent or self.velocities_as_state:
            return ()
        phis = list(self.image.constraints)
        if not phis:
            return ()
        M = self.manifold
        rows = [[M.reduce(self.algebra.bracket(chi, phi)) for phi in phis]
                for chi in self.run.final_constraints]
        kernel = sp.Matrix(rows).nullspace(simplify=True)
        out = []
        for k in kernel:
            den = sp.lcm_list([sp.denom(sp.together(e)) for e in k])
            out.append(cancel(sum((cancel(e * den) * f for e, f in zip(k, phis)), sp.S.Zero)))
        return tuple(out)

    @cached_property
    def gauge_generators(self) -> tuple:
        """One :class:`GaugeGenerator` per primary first-class combination (Castellani);
        none with velocity constraints or forces (their terms are no Hamiltonian field) or
        with t in L (the chain would need the dG/dt terms)."""
        if (self.conditions or self.system.has_forces or self.system.time is not None
                or self.velocities_as_state):
            return ()
        return tuple(self._castellani(g, i + 1) for i, g in enumerate(self.primary_first_class))

    def _castellani(self, gamma, index: int) -> GaugeGenerator:
        """G_K = gamma, G_{k-1} = -{G_k, H'}; where -{G_0, H'} is a combination of the
        primary first-class constraints and their first descendants, G_0 takes the primary
        terms that make {G_0, H'} a primary one (the non-abelian case)."""
        H, M = self.hamiltonian, self.manifold
        pfc = list(self.primary_first_class)
        descend = [cancel(-self.algebra.bracket(f, H)) for f in pfc]
        gens = self.algebra.variables
        chain = [gamma]
        for _ in range(2 * self.n):
            s = cancel(-self.algebra.bracket(chain[-1], H))
            if s == 0 or _combination(s, pfc, gens) is not None:
                break
            if len(chain) > 1:
                coeffs = _combination(s, pfc + descend, gens)
                if coeffs is not None:
                    # -{G_0 + alpha phi, H'} = s + alpha . descendants + (primary terms)
                    alpha = coeffs[len(pfc):]
                    chain[-1] = cancel(chain[-1] - sum((a * f for a, f in zip(alpha, pfc)),
                                                       sp.S.Zero))
                    break
            chain.append(s)
        K = len(chain) - 1
        terms = tuple((K - i, g) for i, g in enumerate(chain))
        G = sum((gauge_parameter_symbol(index, k) * g for k, g in terms), sp.S.Zero)
        moves = tuple((z, d) for z in gens if (d := cancel(self.algebra.bracket(z, G))) != 0)
        checked = Decision(True, "exact", "no constraints")
        for _, g in terms:
            for chi in self.run.final_constraints:
                d = M.vanishes(self.algebra.bracket(g, chi), tol=self.policy.tol)
                if not d.value:
                    checked = d
                    break
                checked = d if checked.detail == "no constraints" or d.method == "sampled" \
                    else checked
            if not checked.value:
                break
        return GaugeGenerator(index=index, terms=terms, transformations=moves,
                              checked=checked)

    @cached_property
    def dirac_bracket(self) -> sp.Matrix | None:
        """{z_i, z_j}_D for z = (q, p) over the maximal second-class set, shape (2n, 2n);
        the canonical matrix when there is no second-class constraint."""
        if self.classes is None:
            return None
        second = self.classes.second_class_constraints or ()
        z = self.algebra.variables
        if not second:
            return sp.Matrix(len(z), len(z), lambda i, j: self.algebra.bracket(z[i], z[j]))
        D = DiracBracket(self.algebra, second)
        return sp.Matrix(len(z), len(z), lambda i, j: sp.factor(D(z[i], z[j])))

    @cached_property
    def equivalence(self):
        """The Lagrangian chain on TQ and its comparison through Leg
        (:func:`nhham.hamiltonian.equivalence.equivalence`); None when inconsistent."""
        from nhham.hamiltonian.equivalence import equivalence

        return equivalence(self) if self.consistent else None

    # ----------------------------------------------------------------- report
    @property
    def warnings(self) -> tuple:
        out = list(self.run.warnings)
        if self.classes is not None:
            out += list(self.classes.warnings)
        if self.image.rank_drops:
            where = ", ".join(f"{f} = 0" for f in self.image.rank_drops)
            out.insert(0, f"rank W is {self.image.rank} generically and may drop where "
                          f"{where}: the primary constraints differ there, the answer is the "
                          f"generic rank's")
        for lab, given, regular in self.replaced:
            out.append(f"{lab}: {given} = 0 is irregular (its gradient vanishes where it "
                       f"holds); the chain used {regular} = 0, the same zero set, and counts "
                       f"degrees of freedom for it")
        if self.irregular:
            out.append("irregular constraints (gradient zero on M_f): "
                       + ", ".join(self.irregular) + "; the count of degrees of freedom "
                       "(2n - 2 FC - SC)/2 does not apply")
        for g in self.gauge_generators:
            if not g.checked.value:
                out.append(f"the gauge generator of {g.terms[0][1]} is not first class on "
                           f"M_f ({g.checked.describe()}): Castellani's chain did not close")
        return tuple(out)


def _combination(expr, basis, gens):
    """Coefficients c with expr = sum c_i basis_i (division with remainder 0), else None."""
    if not basis:
        return None
    try:
        quotients, remainder = sp.reduced(sp.expand(sp.numer(sp.together(expr))),
                                          [sp.expand(b) for b in basis], *gens)
    except (sp.PolynomialError, sp.polys.polyerrors.PolificationFailed, TypeError, ValueError):
        return None
    if remainder != 0:
        return None
    den = sp.denom(sp.together(expr))
    return [cancel(qt / den) for qt in quotients]


def with_parameters(system, sub=None, symbolic=()):
    """``system`` with ``sub`` ({parameter: value}, put in exactly) and the parameters
    named in ``symbolic`` without a value; the others keep theirs.

    Examples
    --------
    >>> from nhham import System
    >>> from nhham.hamiltonian.dirac_bergmann import with_parameters
    >>> s = System(["x"], "a*x_dot**2/2 + b*x", parameters={"a": 1.0, "b": 2.0})
    >>> t = with_parameters(s, {s.parameters[0]: 3}, symbolic=["b"])
    >>> t.lagrangian, dict(t.parameter_values)
    (b*x + 3*x_dot**2/2, {})
    """
    from nhham.system.description import System

    sub = dict(sub or {})
    if not sub and not symbolic:
        return system
    params = {p.name: (None if p.name in symbolic else system.parameter_values.get(p))
              for p in system.declared_parameters if p not in sub}
    forced = system.has_forces
    return System([q.name for q in system.coordinates], system.lagrangian.xreplace(sub),
                  [c.xreplace(sub) for c in system.constraints],
                  holonomic=[g.xreplace(sub) for g in system.holonomic],
                  parameters=params, name=system.name,
                  forces=[f.xreplace(sub) for f in system.forces] if forced else None,
                  dissipation=system.dissipation.xreplace(sub) if forced else None)


def at_parameter_values(system):
    """``system`` with its parameter values put in exactly (as rationals: 9.81 -> 981/100);
    parameters without a value stay symbols. The system itself when none has a value."""
    return with_parameters(system, _exact_values(system))


def _exact_values(system) -> dict:
    """{parameter: its value as a rational} (9.81 -> 981/100)."""
    return {s: sp.Rational(repr(float(v))) for s, v in system.parameter_values.items()}


def dirac_bergmann(system, *, policy: Policy | None = None,
                   max_generations: int | None = None, gauge=()) -> DiracBergmann:
    """Run the Dirac–Bergmann chain of ``system``'s singular Lagrangian at its values.

    Parameters
    ----------
    system : nhham.System
        A Lagrangian at most quadratic in v, with holonomic constraints or none.
    policy : Policy, optional
        The settings of every decision.
    max_generations : int, optional
        Bound on the generations (default 2n).
    gauge : sequence of sympy.Expr, optional
        Gauge conditions chi(q) = 0 in the coordinates and parameters (a scene's
        ``[gauge]``): they join M_1 as ``gauge[i]`` without a multiplier, so their tangency
        fixes free multipliers or adds constraints; a complete gauge leaves none free.

    Returns
    -------
    DiracBergmann

    Raises
    ------
    InputError
        Velocity constraints, forces or a time-dependent L on a singular Lagrangian (not
        built), naming the key.

    Examples
    --------
    A Landau level, L = B x y' - k (x^2 + y^2)/2: two second-class primaries and the
    Dirac bracket {x, y}_D = -1/B.

    >>> from nhham import System
    >>> from nhham.hamiltonian.dirac_bergmann import dirac_bergmann
    >>> db = dirac_bergmann(System(["x", "y"], "B*x*y_dot - k*(x**2 + y**2)/2",
    ...                            parameters={"B": 2.0, "k": 1.0}))
    >>> db.generations, db.second_class, db.degrees_of_freedom
    (((p_x, p_y - 2*x),), 2, 1)
    >>> db.dirac_bracket[0, 1]
    -1/2
    """
    from nhham.lagrangian.algorithm import run_algorithm, square_free

    _refuse_unbuilt(system)
    policy = policy or Policy()
    at = at_parameter_values(system)
    image = legendre_image(at)
    q, p = image.coordinates, image.momenta
    algebra = BracketAlgebra(q, p)
    state = set(q) | set(p)
    replaced = tuple((f"holonomic[{i}]", g, square_free(g, state))
                     for i, g in enumerate(at.holonomic)
                     if not sp.cancel(square_free(g, state) / g).is_number)
    regular = {lab: r for lab, _, r in replaced}
    hol = tuple(regular.get(f"holonomic[{i}]", g) for i, g in enumerate(at.holonomic))
    # multipliers: lambda of the holonomic g, then of the velocity constraints, then u^a
    vel = tuple(at.constraints)
    functions = hol + (None,) * len(vel) + tuple(image.constraints)
    symbols = tuple(multiplier_symbol(i + 1) for i in range(len(hol) + len(vel))) + tuple(
        primary_multiplier_symbol(a + 1) for a in range(len(image.constraints)))
    n = at.n
    # v = dH_T/dp: the velocity constraints are conditions on the motion, affine in u (a
    # Chetaev one does not depend on the velocities along ker W: _refuse_unbuilt)
    HT = image.canonical_hamiltonian + sum(
        (s * f for s, f in zip(symbols, functions) if f is not None), sp.S.Zero)
    v_of = {v: cancel(sp.diff(HT, pa)) for v, pa in zip(at.velocities, p)}
    # the reaction -lambda dphi/dv (Chetaev's rule; mu(q) for an affine phi) at v(q, p)
    mu = [[cancel(sp.diff(c, v).xreplace(v_of)) for v in at.velocities] for c in vel]
    rows = [list(algebra.hamiltonian_field(f).T) if f is not None
            else [0] * n + [-e for e in mu[i - len(hol)]]
            for i, f in enumerate(functions)]
    fields = sp.Matrix(rows) if rows else sp.zeros(0, 2 * n)
    gauge = tuple(sp.sympify(c).xreplace(_exact_values(system)) for c in gauge)
    labels = tuple(f"holonomic[{i}]" for i in range(len(hol))) + tuple(
        f"primary[{a}]" for a in range(len(image.constraints))) + tuple(
        f"gauge[{i}]" for i in range(len(gauge)))
    multiplied = tuple(f for f in functions if f is not None) + gauge
    conditions = tuple((lab, cancel(c.xreplace(v_of)))
                       for lab, c in zip(at.constraint_labels[len(at.holonomic):], vel))

    u = symbols[len(hol) + len(vel):]
    if _nonlinear_in(u, [c for _, c in conditions]
                     + (list(at.generalized_forces.xreplace(v_of)) if at.has_forces else [])):
        return _velocities_as_state(system, at, image, algebra, policy, hol, vel, symbols,
                                    v_of, mu, gauge, replaced, max_generations)
    manifold = _manifolds(at, policy, p)

    base = algebra.hamiltonian_field(image.canonical_hamiltonian)
    if at.has_forces:   # p' gains Q(q, v), v = dH_c/dp + u^a dphi_a/dp: affine in the u^a
        Q = at.generalized_forces
        v_c = {v: cancel(sp.diff(image.canonical_hamiltonian, pa))
               for v, pa in zip(at.velocities, p)}
        base = base + sp.Matrix([0] * n + [cancel(f.xreplace(v_c)) for f in Q])
        dQ = Q.jacobian(list(at.velocities))
        for i in range(len(hol) + len(vel), len(functions)):   # the primaries' u^a
            k = sp.Matrix([sp.diff(functions[i], pa) for pa in p])   # move v along k_a
            push = list((dQ * k).xreplace(v_c))
            rows[i] = rows[i][:n] + [cancel(a + b) for a, b in zip(rows[i][n:], push)]
        fields = sp.Matrix(rows)
    run = run_algorithm(base, fields, multiplied, labels, manifold,
                        max_stages=2 * n if max_generations is None else max_generations,
                        multiplier_symbols=symbols, variables=q + p, points_are_motions=True,
                        field_conditions=conditions, time=at.time)
    return DiracBergmann(system=at, image=image, run=run, multipliers=symbols, policy=policy,
                         replaced=replaced, base_field=base, vertical_fields=fields,
                         functions=functions, conditions=conditions, gauge=gauge)


def _nonlinear_in(u, exprs) -> bool:
    """Whether an expression is not affine in the symbols ``u``."""
    return any(sp.diff(e, a, b) != 0 for e in exprs for a in u for b in u)


def _manifolds(at, policy, fibre):
    """``manifold(equations)``: the M_k of the chain, Submanifolds over q and ``fibre``."""
    def manifold(eqs):
        return Submanifold(at, eqs, precision=policy.precision, samples=policy.samples,
                           seed=policy.seed, fibre=tuple(fibre), exact=policy.exact)
    return manifold


def _velocities_as_state(system, at, image, algebra, policy, hol, vel, symbols, v_of, mu,
                         gauge, replaced, max_generations) -> DiracBergmann:
    """The chain with the u^a as state variables (``DESIGN.md`` §2): on T*Q x R^r the
    field X_{H_c} + u^a X_{phi_a} + (0, Q(q, v)), the multipliers lambda (holonomic and
    velocity reactions) and u_a' (d/du^a); the velocity constraints phi(q, v(q, p, u))
    are constraints there, their tangency affine in the multipliers."""
    from nhham.lagrangian.algorithm import run_algorithm

    q, p = image.coordinates, image.momenta
    n, r = at.n, len(image.constraints)
    u = symbols[len(hol) + len(vel):]
    lam = symbols[: len(hol) + len(vel)]
    rates = tuple(sp.Symbol(f"{a.name}_dot") for a in u)   # u_a' (render/names reads them)
    field = algebra.hamiltonian_field(image.canonical_hamiltonian)
    for a, phi in zip(u, image.constraints):
        field = field + a * algebra.hamiltonian_field(phi)
    if at.has_forces:
        field = field + sp.Matrix([0] * n + list(at.generalized_forces.xreplace(v_of)))
    base = sp.Matrix([cancel(e) for e in field] + [0] * r)
    rows = [list(algebra.hamiltonian_field(g).T) + [0] * r for g in hol]
    rows += [[0] * n + [-e for e in row] + [0] * r for row in mu]   # -lambda dphi/dv at v(u)
    rows += [[0] * (2 * n) + [1 if b == a else 0 for b in range(r)] for a in range(r)]
    fields = sp.Matrix(rows)
    velocity_labels = at.constraint_labels[len(at.holonomic):]
    primary = (hol + tuple(image.constraints)
               + tuple(cancel(c.xreplace(v_of)) for c in vel) + gauge)
    labels = (tuple(f"holonomic[{i}]" for i in range(len(hol)))
              + tuple(f"primary[{a}]" for a in range(r)) + tuple(velocity_labels)
              + tuple(f"gauge[{i}]" for i in range(len(gauge))))

    run = run_algorithm(base, fields, primary, labels, _manifolds(at, policy, tuple(p) + u),
                        max_stages=2 * n + r if max_generations is None else max_generations,
                        multiplier_symbols=lam + rates, variables=tuple(q) + tuple(p) + u,
                        points_are_motions=True, time=at.time)
    return DiracBergmann(system=at, image=image, run=run, multipliers=lam + rates,
                         policy=policy, replaced=replaced, base_field=base,
                         vertical_fields=fields,
                         functions=hol + (None,) * (len(vel) + r), conditions=(),
                         gauge=gauge, velocities_as_state=u)


def _refuse_unbuilt(system) -> None:
    """The parts of a singular system the chain does not take yet, each by its key."""
    problems = []
    if system.inputs:
        problems.append("inputs: inputs on a singular Lagrangian are not handled yet")
    if problems:
        raise InputError("; ".join(problems), key=problems[0].split(":")[0])
