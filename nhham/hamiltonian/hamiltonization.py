"""Hamiltonization of a Chaplygin system by a conformal factor (Chaplygin's multiplier).

On T*S (shape coordinates r, momenta p = dL_c/dr') the reduced motion is X with
i_X Omega_nh = dH_c, where H_c is the energy of L_c and

    Omega_nh = dr^a ^ dp_a - 1/2 J_a B^a_{ab} dr^a ^ dr^b

(:mod:`nhham.lagrangian.chaplygin` for J, B). Omega_nh is not closed when J B is not. A
function f(r) > 0 with d(f Omega_nh) = 0 makes f Omega_nh symplectic, so that X/f is
Hamiltonian for it: the reduced system is Hamiltonian after the change of time
dtau = dt/f (convention: d(f Omega_nh) = 0). Such an f exists exactly when

    theta ^ Omega_nh = -d Omega_nh

has a solution theta that is closed and depends on r alone (then f = exp of its
potential): on 2k >= 4 dimensions wedging with a nondegenerate 2-form is injective on
one-forms, so the linear equations decide theta uniquely when they can be solved. Then
f^(k-1) times the Liouville volume is an invariant measure of X. Everything is decided
exactly, with the Jacobiator of the bracket before and after rescaling.

Two routes, both in the velocity coordinates (r, r') where the equations need no inverse
of the Legendre map (:mod:`nhham.hamiltonian.hamiltonization_points`): the closed form
(sympy's linsolve, theta carried to (r, p)) when Omega_nh is small, else a decision at an
exact point first (a proof of "no factor" by one nonzero value), the closed form only when
the point refutes nothing. With L_c quadratic in r' the components of the equations with
a dp leg force theta's dp part to vanish and read theta_a W_bc - theta_b W_ac =
dG_ab/dr'^c (G = J_a B^a): for k = 2 they always have a solution, for k >= 3 they are a
condition, which the Chaplygin sphere on T*SO(3) and the 3-D disc fail.

Forms are arrays: a 2-form is the antisymmetric matrix Omega with
Omega = 1/2 Omega_ij dz^i ^ dz^j, its exterior derivative has the components
(d Omega)_ijk = d_i Omega_jk + d_j Omega_ki + d_k Omega_ij (i < j < k), and
(theta ^ Omega)_ijk = theta_i Omega_jk + theta_j Omega_ki + theta_k Omega_ij.
The bracket is {F, G} = grad F . Pi grad G with Pi = -Omega^{-1}, so that F' = {F, H}.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import sympy as sp

from nhham.errors import InputError
from nhham.hamiltonian.hamiltonization_points import (
    decide_at_a_point,
    fibre_obstruction,
    jacobiators,
    velocity_equations,
)
from nhham.lagrangian.algebra import cancel, normal_form, tidy_light
from nhham.lagrangian.chaplygin import TIDY_OPS
from nhham.lagrangian.decision import Decision
from nhham.system.expressions import to_text
from nhham.system.naming import momentum_symbol

__all__ = ["Hamiltonization", "hamiltonize"]


@dataclass(frozen=True)
class Hamiltonization:
    """Whether a Chaplygin system is Hamiltonian after a change of time.

    Attributes
    ----------
    reduction : ChaplyginReduction
    variables : tuple of sympy.Symbol
        (r, p) on T*S.
    hamiltonian : sympy.Expr
        H_c(r, p).
    two_form : sympy.Matrix, shape (2k, 2k)
        Omega_nh.
    hamiltonizable : bool
    theta : tuple of sympy.Expr or None
        The solution of theta ^ Omega = -d Omega (components on dr, then dp), or None.
    conformal_factor : sympy.Expr or None
        f(r) with d(f Omega_nh) = 0 (up to a constant factor).
    obstruction : str or None
        Why no factor exists: no solution; theta not closed (with d theta); theta depends
        on p.
    jacobiator_before, jacobiator_after : tuple of (tuple of str, sympy.Expr)
        The nonzero Jacobiators of the coordinate functions (triple, value), before and
        after rescaling Pi to Pi / f (empty: the Jacobi identity holds).
    invariant_measure_density : sympy.Expr or None
        f^(k-1) (times dr dp): div(f^(k-1) X) = 0 checked exactly.
    divergence : sympy.Expr or None
        div(f^(k-1) X), simplified (0 when the measure is invariant).
    decision : Decision
        How the verdict was reached (method ``exact``: the closed form, or a proof at an
        exact point), with the detail.
    route : {"closed form", "exact point"}
        In the route "exact point" ``theta`` is None, ``hamiltonian`` and ``two_form`` are
        left as formed (r' = adj W (p - b) / det W, not cancelled), and
        ``jacobiator_before`` lists the triples whose Jacobiator is nonzero at the point
        (a proof; the others vanish there, which proves nothing), each written in the
        velocity coordinates (r, r') (composed with the Legendre map), as formed.
    """

    reduction: Any
    variables: tuple
    hamiltonian: sp.Expr
    two_form: sp.Matrix
    hamiltonizable: bool
    theta: tuple | None
    conformal_factor: sp.Expr | None
    obstruction: str | None
    jacobiator_before: tuple
    jacobiator_after: tuple
    invariant_measure_density: sp.Expr | None
    divergence: sp.Expr | None
    decision: Decision
    route: str

    def to_dict(self) -> dict:
        def jac(found):
            return [{"triple": list(t), "value": to_text(v)} for t, v in found]

        red = self.reduction
        return {
            "hamiltonizable": self.hamiltonizable,
            "conformal_factor": None if self.conformal_factor is None
            else to_text(self.conformal_factor),
            "invariant_measure_density": None if self.invariant_measure_density is None
            else to_text(self.invariant_measure_density),
            "divergence": None if self.divergence is None else to_text(self.divergence),
            "theta": None if self.theta is None else [to_text(e) for e in self.theta],
            "jacobiator_before": jac(self.jacobiator_before),
            "jacobiator_after": jac(self.jacobiator_after) if self.hamiltonizable else None,
            "obstruction": self.obstruction,
            "shape_coordinates": [to_text(r) for r in red.shape],
            "symmetry_coordinates": [to_text(s) for s in red.symmetry],
            "variables": [to_text(z) for z in self.variables],
            "hamiltonian": to_text(self.hamiltonian),
            "decision": {"route": self.route, **self.decision.to_dict(value=False)},
        }


def hamiltonize(reduction, *, part=None) -> Hamiltonization:
    """Decide whether a Chaplygin reduction has a conformal factor, and find it.

    The equations are formed in the velocity coordinates (r, r')
    (:mod:`nhham.hamiltonian.hamiltonization_points`): no inverse of the Legendre map is
    needed for them. Where Omega_nh is small (``CLOSED_FORM_OPS``) they are solved in
    closed form; otherwise they are first decided at an exact point, where one nonzero
    value proves that no factor exists, and the closed form is sought only when the point
    refutes nothing.

    Parameters
    ----------
    reduction : ChaplyginReduction
        From :func:`nhham.lagrangian.chaplygin.chaplygin_reduction`.
    part : callable, optional
        Called with the name of each part as it begins (a command's progress).

    Returns
    -------
    Hamiltonization

    Examples
    --------
    The nonholonomic particle z' = y x': Omega_nh = dx^dp_x + dy^dp_y - J dx^dy with
    J = y p_x/(1 + y^2); theta = -y/(1 + y^2) dy is closed, so f = (1 + y^2)^(-1/2).

    >>> from nhham import System
    >>> from nhham.lagrangian.chaplygin import chaplygin_reduction
    >>> particle = System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2",
    ...                   ["z_dot - y*x_dot"])
    >>> found = hamiltonize(chaplygin_reduction(particle))
    >>> found.hamiltonizable, found.conformal_factor
    (True, 1/sqrt(y**2 + 1))
    >>> found.jacobiator_before, found.jacobiator_after   # {p_x, p_y} = J, dJ/dp_x
    (((('x', 'p_x', 'p_y'), -y/(y**2 + 1)),), ())
    """
    say = part or (lambda what: None)
    red = reduction
    rdot = list(red.shape_velocities)
    k = len(rdot)
    W = sp.Matrix(k, k, lambda i, j: sp.diff(red.lagrangian, rdot[i], rdot[j]))
    if any(e.free_symbols & set(rdot) for e in W):
        raise InputError("hamiltonize: L_c is not quadratic in the shape velocities (its "
                         "Legendre map would need a nonlinear inverse)", key="lagrangian")
    say("theta ^ Omega_nh = -d Omega_nh in the velocity coordinates (r, r')")
    eqs = velocity_equations(red)
    if eqs.size() > CLOSED_FORM_OPS:
        say("the equations at an exact point")
        verdict = decide_at_a_point(eqs, red.system)
        if verdict is not None and verdict.proof is not None:
            return _at_a_point(red, eqs, verdict)
    if k == 2 and eqs.size() > CLOSED_FORM_OPS:
        say("theta on a surface, its closedness and the factor (normal forms)")
        return _on_a_large_surface(red, eqs)
    say("theta in closed form, the factor and the Jacobiators")
    return _closed_form(red, eqs)


#: Largest Omega_nh (sympy operations of its upper triangle in (r, r')) solved in closed
#: form before a decision at an exact point (the sleigh: 63; the 3-D disc: 87; the Chaplygin
#: sphere: 423).
CLOSED_FORM_OPS = 200

_CLOSED = "closed form"
_POINT = "exact point"


def _legendre(red, eqs, *, tidy=True) -> dict:
    """r' = W^{-1} (p - b) as a substitution (cancelled when ``tidy``; else adj W / det W
    as formed, for large data that are only printed)."""
    momenta = sp.Matrix([momentum_symbol(r) for r in eqs.shape])
    b = sp.Matrix(eqs.momenta).xreplace({w: 0 for w in eqs.velocities})
    if tidy:
        v_of_p = eqs.W.LUsolve(momenta - b).applyfunc(cancel)
    else:
        v_of_p = eqs.W.adjugate() * (momenta - b) / eqs.W.det(method="berkowitz")
    return dict(zip(eqs.velocities, v_of_p))


def _energy(red, eqs, to_p, tidy=True) -> sp.Expr:
    """H_c(r, p); untidied: 1/2 (p - b)^T adj W (p - b) / det W - L_c(r, 0), the energy of
    L_c = 1/2 r'^T W r' + b r' + L_c(r, 0) without substituting r' into each term."""
    if not tidy:
        zero = {w: 0 for w in eqs.velocities}
        shifted = sp.Matrix([momentum_symbol(r) for r in eqs.shape]) \
            - sp.Matrix(eqs.momenta).xreplace(zero)
        W = sp.Matrix(eqs.W)
        quadratic = (shifted.T * W.adjugate() * shifted)[0, 0]
        return quadratic / (2 * W.det(method="berkowitz")) - red.lagrangian.xreplace(zero)
    energy = sum((w * sp.diff(red.lagrangian, w) for w in eqs.velocities), sp.S.Zero) \
        - red.lagrangian
    return cancel(energy.xreplace(to_p))


def _two_form(eqs, to_p, tidy=True) -> sp.Matrix:
    """Omega_nh on T*S: [[-G(r, p), 1], [-1, 0]]."""
    k = eqs.k
    Omega = sp.zeros(2 * k, 2 * k)
    for a in range(k):
        Omega[a, k + a], Omega[k + a, a] = 1, -1
    for a, c in itertools.product(range(k), repeat=2):
        g = -eqs.gyroscopic[a, c].xreplace(to_p)
        Omega[a, c] = cancel(g) if tidy else g
    return Omega


def _at_a_point(red, eqs, verdict) -> Hamiltonization:
    """The verdict of an exact point that proved the obstruction."""
    to_p = _legendre(red, eqs, tidy=False)
    z = eqs.shape + tuple(momentum_symbol(r) for r in eqs.shape)
    lead = {"no solution": "the equations theta ^ Omega_nh = -d Omega_nh have no solution",
            "dp part": "theta depends on the momenta p (its dp part)",
            "depends on p": "theta depends on the momenta p (its dp part or its "
                            "coefficients)",
            "not closed": "theta is not closed"}[verdict.proof]
    values = red.system.parameter_values
    scope = (" (the parameters at the scene's values: " + ", ".join(
        f"{p} = {v}" for p, v in values.items()) + ")") if values else ""
    obstruction = f"{lead}: decided at an exact point{scope}: {verdict.detail}"
    decision = Decision(False, "exact", f"{_POINT}: {verdict.detail}; the point: "
                        f"{verdict.point}")
    Omega = _two_form(eqs, to_p, tidy=False)
    before = _jacobiators_in_velocities(eqs, [t for t, _ in verdict.jacobiator])
    return Hamiltonization(red, z, _energy(red, eqs, to_p, tidy=False),
                           Omega, False, None, None, obstruction,
                           before, (), None, None, decision, _POINT)


def _jacobiators_in_velocities(eqs, triples) -> tuple:
    """The Jacobiators of ``triples`` in closed form in (r, r') (composed with Leg), as
    formed: W^{-1} = adj W / det W."""
    det = sp.Dummy("det")
    W = sp.Matrix(eqs.W)
    inverse = (W.adjugate() / det).tolist()
    found = jacobiators(eqs, list, lambda _: inverse, triples)
    value_of_det = W.det(method="berkowitz")
    # shown to people: the cheap reductions modulo sin^2 + cos^2 = 1 where small enough
    return tuple((t, tidy_light(v.xreplace({det: value_of_det}), TIDY_OPS)) for t, v in found)


def _closed_form(red, eqs) -> Hamiltonization:
    k = eqs.k
    to_p = _legendre(red, eqs)
    z = list(eqs.shape) + [momentum_symbol(r) for r in eqs.shape]
    H = _energy(red, eqs, to_p)
    Omega = _two_form(eqs, to_p)
    theta, obstruction, f = _conformal_factor(eqs, to_p, z, k, Omega,
                                              red.system.parameter_values)
    Pi = _bracket(Omega, k)
    before = _jacobiators(Pi, z)
    if theta is None and k >= 2:  # theta's dp part vanishes: the dp-leg components say why
        reason = fibre_obstruction(eqs.shape, before)
        obstruction += f": {reason}" if reason else ""
    after = _rescaled_jacobiators(Pi, z, theta[:k]) if f is not None else ()
    density = divergence = None
    if f is not None:
        density = f ** (k - 1) if f.is_Mul or f.is_Pow else sp.simplify(f ** (k - 1))
        divergence = _divergence(Pi, H, z, theta[:k], k)
    how = ("theta read off Omega_nh (k = 2: theta = -d omega/dp_2 dr^1 + d omega/dp_1 dr^2, "
           "omega = Omega_nh(r^1, r^2)); d theta and the Jacobiators decided by the normal "
           "form modulo sin^2 + cos^2 = 1") if k == 2 else (
        "theta ^ Omega_nh = -d Omega_nh solved in the velocity coordinates (r, r') and "
        "carried to (r, p)")
    decision = Decision(f is not None and not after, "exact", f"{_CLOSED}: {how}")
    return Hamiltonization(red, tuple(z), H, Omega, f is not None and not after, theta, f,
                           obstruction, before, after, density, divergence, decision, _CLOSED)


def _on_a_large_surface(red, eqs) -> Hamiltonization:
    """k = 2 with a large Omega_nh (the second steps of the Chaplygin and rubber balls):
    G = G(r, r') is linear in r', so with g_c = dG_12/dr'^c and r' = W^{-1} (p - b),
    theta_1 = dG_12/dp_2 = (g W^{-1})_2 and theta_2 = -dG_12/dp_1 = -(g W^{-1})_1
    (no inverse Legendre map cancelled: adj W / det W, then one normal form each). The
    only Jacobiators of Pi = [[0, 1], [-1, G]] that can be nonzero are
    J(r^c, p_1, p_2) = -dG_12/dp_c, i.e. theta_2 and -theta_1; after rescaling they vanish
    by the theorem (theta solves theta ^ Omega = -d Omega exactly, so d(f Omega) =
    f (theta ^ Omega + d Omega) = 0 once theta is closed), and f is then an invariant
    density (the Liouville measure of f Omega_nh, preserved by X/f)."""
    k = 2
    z = tuple(eqs.shape) + tuple(momentum_symbol(r) for r in eqs.shape)
    W = sp.Matrix(eqs.W)
    det, adj = W.det(method="berkowitz"), W.adjugate()
    g = [sp.diff(eqs.gyroscopic[0, 1], w) for w in eqs.velocities]
    if any(e.free_symbols & set(eqs.velocities) for e in g):  # pragma: no cover - G is J B
        raise InputError("hamiltonize: the gyroscopic form is not linear in the shape "
                         "velocities", key="lagrangian")
    theta = (_tidy((g[0] * adj[0, 1] + g[1] * adj[1, 1]) / det),
             _tidy(-(g[0] * adj[0, 0] + g[1] * adj[1, 0]) / det), sp.S.Zero, sp.S.Zero)
    before = tuple(((str(z[c]), str(z[2]), str(z[3])), value)
                   for c, value in ((0, theta[1]), (1, -theta[0])) if value != 0)
    _, obstruction, f = _closed_and_exact(theta, z, k, red.system.parameter_values)
    to_p = _legendre(red, eqs, tidy=False)
    how = ("theta read off Omega_nh (k = 2: theta = (g W^-1)_2 dr^1 - (g W^-1)_1 dr^2, "
           "g = dG_12/dr'); d theta decided by the normal form modulo sin^2 + cos^2 = 1; "
           "the rescaled bracket Poisson and f an invariant density by the theorem "
           "(d(f Omega_nh) = 0)")
    return Hamiltonization(red, z, _energy(red, eqs, to_p, tidy=False),
                           _two_form(eqs, to_p, tidy=False), f is not None, theta, f,
                           obstruction, before, (), f, sp.S.Zero if f is not None else None,
                           Decision(f is not None, "exact", f"{_CLOSED}: {how}"), _CLOSED)


def _bracket(Omega, k) -> sp.Matrix:
    """Pi = -Omega^{-1} of Omega = [[-G, 1], [-1, 0]]: [[0, 1], [-1, G]], i.e.
    {r^a, p_b} = delta_ab and {p_a, p_b} = G_ab (no inverse formed)."""
    Pi = sp.zeros(2 * k, 2 * k)
    for a in range(k):
        Pi[a, k + a], Pi[k + a, a] = 1, -1
    Pi[k:, k:] = -Omega[:k, :k]
    return Pi


def _three_indices(size):
    return itertools.combinations(range(size), 3)


def _conformal_factor(eqs, to_p, z, k, Omega, values) -> tuple:
    """(theta or None, obstruction or None, f or None) from theta ^ Omega = -d Omega,
    solved in (r, r') and carried to (r, p): theta_p = W^{-1} (dr' part),
    theta_r = (dr part) - (dp/dr)^T theta_p; for k = 2 read off Omega directly."""
    if k == 2:
        return _closed_and_exact(_theta_on_a_surface(Omega, z), z, k, values)
    size = 2 * k
    t = sp.symbols(f"theta0:{size}")
    # coefficient by coefficient: cheaper than cancelling the rows with theta inside
    equations = [sum((cancel(a) * x for a, x in zip(row, t)), sp.S.Zero) - cancel(rhs)
                 for row, rhs in zip(eqs.A, eqs.b)]
    equations = [e for e in equations if e != 0]
    solution = sp.linsolve(equations, t) if equations \
        else sp.FiniteSet(tuple(sp.S.Zero for _ in t))
    if solution == sp.S.EmptySet:
        return None, "the equations theta ^ Omega_nh = -d Omega_nh have no solution", None
    theta_v = next(iter(solution))
    if any(e.free_symbols & set(t) for e in theta_v):  # pragma: no cover - injective, 2k >= 4
        return theta_v, "theta is not determined by the equations", None
    theta_p = eqs.W.LUsolve(sp.Matrix(theta_v[k:]))
    dpdr = sp.Matrix(k, k, lambda c, d: sp.diff(eqs.momenta[c], eqs.shape[d]))
    theta_r = sp.Matrix(theta_v[:k]) - dpdr.T * theta_p
    theta = tuple(_tidy(e.xreplace(to_p)) for e in list(theta_r) + list(theta_p))
    return _closed_and_exact(theta, z, k, values)


def _theta_on_a_surface(Omega, z) -> tuple:
    """theta for k = 2 (by hand: with omega = Omega[r1, r2], the dr^dr^dp components of
    theta ^ Omega = -d Omega read theta_1 = -d omega/dp_2, theta_2 = d omega/dp_1, and the
    dp^dp ones make the dp part 0): no linear solve."""
    omega = Omega[0, 1]
    return (_tidy(-sp.diff(omega, z[3])), _tidy(sp.diff(omega, z[2])), sp.S.Zero, sp.S.Zero)


def _closed_and_exact(theta, z, k, values) -> tuple:
    """(theta, obstruction, f): theta free of p and closed (decided by the normal form
    modulo sin^2 + cos^2 = 1), then f = exp of its potential."""
    if any(not _vanishes(e) for e in theta[k:]) or any(
            e.free_symbols & set(z[k:]) for e in theta[:k]):
        return theta, "theta depends on the momenta p (its dp part or its coefficients)", None
    pairs = list(itertools.combinations(range(k), 2))
    dtheta = [sp.diff(theta[b], z[a]) - sp.diff(theta[a], z[b]) for a, b in pairs]
    open_ = [((a, b), e) for (a, b), e in zip(pairs, dtheta) if not _vanishes(e)]
    if open_:
        shown = "; ".join(f"d{z[a]}^d{z[b]}: {_tidy(e)}" for (a, b), e in open_)
        return theta, f"theta is not closed: d theta = {shown}", None
    return theta, None, _factor(theta[:k], z[:k], values)


def _tidy(e) -> sp.Expr:
    """The normal form modulo sin^2 + cos^2 = 1 (cancelled), or e cancelled."""
    form = normal_form(e)
    return cancel(e) if form is e else form


def _vanishes(e) -> bool:
    """e == 0 as a function, decided exactly: its normal form modulo sin^2 + cos^2 = 1
    (a normal form: zero exactly when e is), else cancel and simplify."""
    e = sp.sympify(e)
    if e == 0:
        return True
    form = normal_form(e)
    if form is not e:
        return form == 0
    return sp.simplify(cancel(e)) == 0


def _factor(theta, r, values) -> sp.Expr:
    """f = exp(phi) with d phi = theta: first as a product of powers of the irreducible
    factors P_j of theta's denominators (theta = sum c_j d ln P_j, the constants c_j from
    exact values, the identity checked exactly), else by integration."""
    found = _logarithmic_potential(theta, r, values)
    if found is not None:
        return found
    return sp.simplify(sp.exp(_potential(theta, r)))


def _logarithmic_potential(theta, r, values):
    factors = []
    for e in theta:
        _, den = sp.fraction(sp.together(e))
        for base, _ in sp.factor_list(den)[1]:
            if base.free_symbols & set(r) and base not in factors:
                factors.append(base)
    if not factors:
        return None
    c = sp.symbols(f"c0:{len(factors)}")
    logs = [[sp.diff(P, x) / P for P in factors] for x in r]
    residual = [t - sum((cj * g for cj, g in zip(c, row)), sp.S.Zero)
                for t, row in zip(theta, logs)]
    equations = []
    points = _rational_points(r, theta, 2 * len(factors) + 2)
    if not points:
        return None
    for point in points:
        equations += [e.xreplace(point) for e in residual]
    solution = sp.linsolve([e for e in equations if e.free_symbols & set(c)], c)
    if not solution or solution == sp.S.EmptySet:
        return None
    values = next(iter(solution))
    if any(v.free_symbols for v in values):
        return None
    if not all(_vanishes(e.xreplace(dict(zip(c, values)))) for e in residual):
        return None
    # each factor with the sign it has at a point, the parameters at their values (f > 0;
    # f is defined up to a constant)
    at = dict(values.items()) if hasattr(values, "items") else {}
    signs = [sp.sign(P.xreplace(points[0]).xreplace(at)) for P in factors]
    signs = [sg if sg.is_number else 1 for sg in signs]
    return sp.Mul(*((sg * P) ** v for P, v, sg in zip(factors, values, signs) if v != 0))


def _rational_points(r, exprs, count):
    """``count`` exact points where sin and cos of every r are rational (Pythagorean:
    t -> (2t, 1 - t^2)/(1 + t^2)) and the expressions are defined."""
    import random

    rng = random.Random(20261127)
    trig = set().union(*(e.atoms(sp.sin, sp.cos) for e in exprs))
    if any(a.args[0] not in r for a in trig):  # sin(2 u), sin(u + v): not by this route
        return []
    out: list = []
    for _ in range(20 * count):
        if len(out) == count:
            break
        point = {}
        for x in r:  # x and (cos x, sin x) are algebraically independent: drawn apart
            t = sp.Rational(rng.randint(1, 97), rng.randint(98, 199))
            point.update({sp.sin(x): 2 * t / (1 + t ** 2), sp.cos(x): (1 - t ** 2) / (1 + t ** 2)})
            point[x] = sp.Rational(rng.randint(1, 97), 53)
        values = [e.xreplace(point) for e in exprs]
        if not any(v.has(sp.zoo, sp.nan, sp.oo) for v in values):
            out.append(point)
    return out


def _rescaled_jacobiators(Pi, z, theta) -> tuple:
    """The Jacobiators of Pi/f with df = f theta (f a function of r; 1/f's derivatives
    -theta/f): f^2 J(Pi/f) is formed and decided by the normal form."""
    k = len(theta)
    F = sp.Function("F")(*z[:k])
    f_value = sp.Dummy("f")
    rescaled = Pi / F
    found = []
    for i, j, l in _three_indices(len(z)):
        value = _jacobiator(rescaled, z, i, j, l) * F ** 2
        value = value.xreplace({sp.Derivative(F, z[a]): F * theta[a] for a in range(k)})
        value = cancel(value.xreplace({F: f_value}))
        assert not value.has(f_value), value  # f^2 J(Pi/f) is free of f once df = f theta
        if not _vanishes(value):
            found.append(((str(z[i]), str(z[j]), str(z[l])), _tidy(value)))
    return tuple(found)


def _divergence(Pi, H, z, theta, k) -> sp.Expr:
    """div(f^(k-1) X) / f^(k-1) = (k - 1) theta . X_r + div X (X = Pi dH), in normal form:
    0 when f^(k-1) is an invariant density."""
    X = Pi * sp.Matrix([sp.diff(H, w) for w in z])
    value = sum(((k - 1) * theta[a] * X[a] for a in range(k)), sp.S.Zero) + sum(
        (sp.diff(X[i], w) for i, w in enumerate(z)), sp.S.Zero)
    return sp.S.Zero if _vanishes(value) else _tidy(value)


def _jacobiator(Pi, z, i, j, l) -> sp.Expr:
    """{{z_i, z_j}, z_l} + cyclic, as formed."""
    value = sum((Pi[i, m] * sp.diff(Pi[j, l], z[m]) + Pi[j, m] * sp.diff(Pi[l, i], z[m])
                 + Pi[l, m] * sp.diff(Pi[i, j], z[m]) for m in range(len(z))), sp.S.Zero)
    return -value  # the sum is {a, {b, c}} + cyclic = -({{a, b}, c} + cyclic)


def _potential(theta, r) -> sp.Expr:
    """phi with d phi = theta for a closed theta(r)."""
    phi = sp.S.Zero
    for i, ri in enumerate(r):
        rest = cancel(theta[i] - sp.diff(phi, ri))
        if rest != 0:
            phi += sp.integrate(rest, ri)
    return phi


def _jacobiators(Pi, z) -> tuple:
    """((names of the triple), value) for every triple of coordinate functions whose
    Jacobiator {{a, b}, c} + cyclic does not vanish."""
    size = len(z)
    found = []
    for i, j, l in _three_indices(size):
        value = cancel(_jacobiator(Pi, z, i, j, l))
        if value != 0:
            found.append(((str(z[i]), str(z[j]), str(z[l])), sp.simplify(value)))
    return tuple(found)
