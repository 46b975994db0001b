"""The numeric Hamiltonized field of a scene (``simulate --method hamiltonized``).

:func:`hamiltonized_field` reduces the scene (:func:`nhham.journeys.reduction.reduction_of`,
the symmetry and the further steps as ``nhham hamiltonize`` takes them), decides whether a
conformal factor f exists (:func:`nhham.hamiltonian.hamiltonization.hamiltonize`) and,
where it does, writes the pieces :mod:`nhham.numerics.hamiltonized` integrates as numeric
functions at the scene's parameter values: H~(r, P) = H_c(r, P/f) and its gradient, f,
the lift q' = T(q) r' through every reduction step, and p = dL_c/dr'. Where there is no
factor the refusal names the obstruction.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from nhham.errors import InputError
from nhham.numerics.hamiltonized import HamiltonizedField

__all__ = ["hamiltonized_field"]


def _lift(red, system):
    """T (n x k) with q' = T(q) r' for the final shape r: each further step's c' = -A2 r~'
    and then the first step's s' = -A r', composed from the last step back."""
    rdot = sp.symbols(f"_rdot0:{len(red.shape)}")
    velocity = dict(zip(red.shape, rdot))
    stage = red
    while hasattr(stage, "previous"):      # a further step: c' = -A2 r~'
        own = sp.Matrix([velocity[c] for c in stage.shape])
        velocity.update(zip(stage.eliminated, -stage.connection * own))
        stage = stage.previous
    own = sp.Matrix([velocity[c] for c in stage.shape])   # the first: s' = -A r'
    velocity.update(zip(stage.symmetry, -stage.connection * own))
    return sp.Matrix([[sp.diff(velocity[q], w) for w in rdot] for q in system.coordinates])


def hamiltonized_field(system, *, symmetry=None, then=None, level=None, steps=None):
    """(HamiltonizedField, Hamiltonization) of ``system`` (parameters at their values).

    Raises
    ------
    InputError
        Where the reduction leaves constraints on the shape space, or no conformal factor
        exists (naming the obstruction), or the factor is not positive at the values.
    """
    from nhham.hamiltonian.hamiltonization import hamiltonize
    from nhham.journeys.reduction import reduction_of

    red = reduction_of(system, symmetry=symmetry, then=then, level=level, steps=steps)
    if red.constraints.rows:
        raise InputError("method hamiltonized: constraints are left on the shape space; "
                         "name the further steps with simulate.then (--then)", key="method")
    found = hamiltonize(red)
    if not found.hamiltonizable:
        raise InputError(f"method hamiltonized: no conformal factor ({found.obstruction}); "
                         f"the reduced system is not Hamiltonian in any rescaled time; use "
                         f"discrete_gradient or rattle", key="method")
    values = system.numeric_parameters()
    k = len(red.shape)
    r, p = list(found.variables[:k]), list(found.variables[k:])
    P = sp.symbols(f"_P0:{k}")
    f = sp.sympify(found.conformal_factor).xreplace(values)
    H = sp.sympify(found.hamiltonian).xreplace(values).xreplace(
        {pa: Pa / f for pa, Pa in zip(p, P)})
    grad = [sp.diff(H, x) for x in r] + [sp.diff(H, x) for x in P]
    q = list(system.coordinates)
    T = _lift(red, system).xreplace(values)
    rdot = list(red.shape_velocities)
    momenta = [sp.diff(red.lagrangian, w).xreplace(values) for w in rdot]
    numeric = dict(modules="math")
    H_f = sp.lambdify([r, P], H, **numeric)
    g_f = sp.lambdify([r, P], grad, **numeric)
    f_f = sp.lambdify([r], f, **numeric)
    T_f = sp.lambdify([q], T, modules="numpy")
    m_f = sp.lambdify([r, rdot], momenta, **numeric)
    def gradient(rv, Pv):
        out = g_f(list(rv), list(Pv))
        return np.asarray(out[:k], dtype=float), np.asarray(out[k:], dtype=float)

    index = {c: i for i, c in enumerate(q)}
    shape = tuple(index[c] for c in red.shape)
    field = HamiltonizedField(
        shape=shape, group=tuple(i for i in range(len(q)) if i not in shape),
        hamiltonian=lambda rv, Pv: float(H_f(list(rv), list(Pv))), gradient=gradient,
        factor=lambda rv: float(f_f(list(rv))),
        lift=lambda qv: np.asarray(T_f(list(qv)), dtype=float),
        momenta=lambda rv, wv: np.asarray(m_f(list(rv), list(wv)), dtype=float),
        factor_text=str(found.conformal_factor))
    return field, found
