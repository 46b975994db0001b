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
exactly (sympy), with the Jacobiator of the bracket before and after rescaling.

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
from nhham.lagrangian.algebra import cancel
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
        }


def hamiltonize(reduction) -> Hamiltonization:
    """Decide whether a Chaplygin reduction has a conformal factor, and find it.

    Parameters
    ----------
    reduction : ChaplyginReduction
        From :func:`nhham.lagrangian.chaplygin.chaplygin_reduction`.

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
    red = reduction
    shape, rdot = list(red.shape), list(red.shape_velocities)
    k = len(shape)
    momenta = [momentum_symbol(r) for r in shape]
    z = shape + momenta
    W = sp.Matrix(k, k, lambda i, j: sp.diff(red.lagrangian, rdot[i], rdot[j]))
    if any(e.free_symbols & set(rdot) for e in W):
        raise InputError("hamiltonize: L_c is not quadratic in the shape velocities (its "
                         "Legendre map would need a nonlinear inverse)", key="lagrangian")
    p_of_v = sp.Matrix([sp.diff(red.lagrangian, w) for w in rdot])
    # L_c quadratic in r' (mechanical): r' = W^{-1} (p - b)
    b = p_of_v.xreplace({w: 0 for w in rdot})
    v_of_p = W.LUsolve(sp.Matrix(momenta) - b).applyfunc(cancel)
    to_p = dict(zip(rdot, v_of_p))
    energy = sum((w * sp.diff(red.lagrangian, w) for w in rdot), sp.S.Zero) - red.lagrangian
    H = cancel(energy.xreplace(to_p))
    G = red.gyroscopic_form
    Omega = sp.zeros(2 * k, 2 * k)
    for a in range(k):
        Omega[a, k + a], Omega[k + a, a] = 1, -1
    for a, c in itertools.product(range(k), repeat=2):
        Omega[a, c] = cancel(-G[a, c].xreplace(to_p))
    theta, obstruction, f = _conformal_factor(Omega, z, k)
    Pi = (-Omega.inv()).applyfunc(cancel)
    before = _jacobiators(Pi, z)
    after = _jacobiators((Pi / f).applyfunc(cancel), z) if f is not None else ()
    density = divergence = None
    if f is not None:
        density = sp.simplify(f ** (k - 1))
        X = Pi * sp.Matrix([sp.diff(H, w) for w in z])
        divergence = sp.simplify(sum((sp.diff(density * X[i], w) for i, w in enumerate(z)),
                                     sp.S.Zero))
    return Hamiltonization(red, tuple(z), H, Omega, f is not None and not after, theta, f,
                           obstruction, before, after, density, divergence)


def _three_indices(size):
    return itertools.combinations(range(size), 3)


def _conformal_factor(Omega, z, k) -> tuple:
    """(theta or None, obstruction or None, f or None) from theta ^ Omega = -d Omega."""
    size = 2 * k
    if size < 4:  # a 2-form on a surface is closed: f = 1
        return (sp.S.Zero, sp.S.Zero), None, sp.S.One
    t = sp.symbols(f"theta0:{size}")
    eqs = []
    for i, j, l in _three_indices(size):
        d = sp.diff(Omega[j, l], z[i]) + sp.diff(Omega[l, i], z[j]) + sp.diff(Omega[i, j], z[l])
        wedge = t[i] * Omega[j, l] + t[j] * Omega[l, i] + t[l] * Omega[i, j]
        eqs.append(cancel(wedge + d))
    solution = sp.linsolve([e for e in eqs if e != 0], t) if any(e != 0 for e in eqs) \
        else sp.FiniteSet(tuple(sp.S.Zero for _ in t))
    if solution == sp.S.EmptySet:
        return None, "the equations theta ^ Omega_nh = -d Omega_nh have no solution", None
    theta = tuple(sp.simplify(cancel(e)) for e in next(iter(solution)))
    if any(e.free_symbols & set(t) for e in theta):  # pragma: no cover - injective for 2k >= 4
        return theta, "theta is not determined by the equations", None
    if any(e != 0 for e in theta[k:]) or any(e.free_symbols & set(z[k:]) for e in theta[:k]):
        return theta, "theta depends on the momenta p (its dp part or its coefficients)", None
    dtheta = [cancel(sp.diff(theta[b], z[a]) - sp.diff(theta[a], z[b]))
              for a, b in itertools.combinations(range(k), 2)]
    dtheta = [e if e == 0 else sp.simplify(e) for e in dtheta]
    if any(e != 0 for e in dtheta):
        shown = "; ".join(f"d{z[a]}^d{z[b]}: {e}" for (a, b), e in
                          zip(itertools.combinations(range(k), 2), dtheta) if e != 0)
        return theta, f"theta is not closed: d theta = {shown}", None
    return theta, None, sp.simplify(sp.exp(_potential(theta[:k], z[:k])))


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
        value = sum((Pi[i, m] * sp.diff(Pi[j, l], z[m]) + Pi[j, m] * sp.diff(Pi[l, i], z[m])
                     + Pi[l, m] * sp.diff(Pi[i, j], z[m]) for m in range(size)), sp.S.Zero)
        value = cancel(-value)  # the sum is {a, {b, c}} + cyclic = -({{a, b}, c} + cyclic)
        if value != 0:
            found.append(((str(z[i]), str(z[j]), str(z[l])), sp.simplify(value)))
    return tuple(found)
