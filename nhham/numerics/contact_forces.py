"""Constraint forces at contact points, from the multipliers.

The equations of motion are W a + μᵀ λ = F (DESIGN.md): the constraints act on the
system through the generalized force Q_c = −μᵀ λ (d/dt ∂L/∂v − ∂L/∂q = −λ^i μ_iA). A
force f_P at a point P whose material velocity is v_P = J_P v + j_P (J_P of shape
(3, n)) acts through the generalized force J_Pᵀ f_P (virtual power f_P · v_P). So the
force of the constraints a contact carries (rows c of φ, see
:mod:`nhham.system.contacts`) is the f_P with

    J_Pᵀ f_P = −μ_cᵀ λ_c,

solved in the least-squares sense. When those constraints are v_P · e_k = 0 with
velocity-free directions e_k, μ_c = E J_P and f_P = −Eᵀ λ_c solves it exactly: the
relative residual |J_Pᵀ f_P + μ_cᵀ λ_c| / |μ_cᵀ λ_c| is then at rounding level, and a
large one says the constraints are not those of the point (reported, never hidden).
f_P is unique when J_P has rank 3 (the point's velocity reaches every direction).

Note what minimal coordinates hide: a contact built into the coordinates (the bicycle's
rear wheel height) has no constraint and no multiplier, so its force is not among these
(force and moment balance of the whole body give it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ContactForces", "contact_forces"]

#: A relative residual above this says the constraints are not the point's (warned).
RESIDUAL_WARNING = 1e-8


@dataclass(frozen=True)
class ContactForces:
    """Forces of the constraints at their contact points, at K states.

    Attributes
    ----------
    points : tuple of str
        The contact points' names.
    forces : dict
        name -> array of shape (K, 3): f_P in the inertial frame at each state.
    residuals : dict
        name -> array of shape (K,): the relative residual ``norm(J_P^T f_P +
        mu_c^T lambda_c) / norm(mu_c^T lambda_c)`` (0 where the constraint force
        vanishes).
    rank : dict
        name -> the smallest rank of J_P over the states (3: f_P is unique).
    warnings : tuple of str

    Examples
    --------
    >>> import sympy as sp
    >>> from nhham import ContactPoint, models
    >>> sleigh = models.chaplygin_sleigh()
    >>> theta, (x_dot, y_dot, theta_dot), a = sleigh.coordinates[2], sleigh.velocities, sp.Symbol("a")
    >>> blade = ContactPoint("blade", (x_dot + a * sp.sin(theta) * theta_dot,
    ...                                y_dot - a * sp.cos(theta) * theta_dot, 0), ("constraints[0]",))
    >>> from nhham import contact_forces, numeric_model
    >>> model = numeric_model(sleigh, backend="numpy")
    >>> y = model.state(dict(x=0.0, y=0.0, theta=0.0, x_dot=1.0, y_dot=0.5, theta_dot=1.0))
    >>> forces = contact_forces(sleigh, [blade], y, model.multipliers(y))
    >>> forces.points, forces.rank      # the vertical force is no constraint's
    (('blade',), {'blade': 2})
    >>> forces.warnings
    ("contacts.blade: the point's velocity map has rank 2 < 3: ...",)
    """

    points: tuple
    forces: dict
    residuals: dict
    rank: dict
    warnings: tuple = ()

    def to_dict(self) -> dict:
        """JSON-ready: per contact the force rows and the largest residual."""
        return {name: {"force": self.forces[name].tolist(),
                       "max_residual": float(np.max(self.residuals[name], initial=0.0)),
                       "rank": int(self.rank[name])} for name in self.points} | (
            {"warnings": list(self.warnings)} if self.warnings else {})


def contact_forces(system, contacts, states, multipliers, parameters=None) -> ContactForces:
    """The force each contact's constraints exert at its point.

    Parameters
    ----------
    system : nhham.System
    contacts : sequence of ContactPoint
        The points and the constraints they carry (a scene's ``contacts``).
    states : array_like, shape (2n,) or (K, 2n)
        (q, v) at each state.
    multipliers : array_like, shape (m,) or (K, m)
        λ at the same states (``NumericModel.multipliers``; for a simulation,
        ``result.states`` and ``result.multipliers.T``).
    parameters : mapping, optional
        Parameter values (symbol or name -> number) where they differ from the
        system's (as given to ``simulate``).

    Returns
    -------
    ContactForces

    Examples
    --------
    >>> import sympy as sp
    >>> from nhham import ContactPoint, models
    >>> sleigh = models.chaplygin_sleigh()
    >>> theta, (x_dot, y_dot, theta_dot), a = sleigh.coordinates[2], sleigh.velocities, sp.Symbol("a")
    >>> blade = ContactPoint("blade", (x_dot + a * sp.sin(theta) * theta_dot,
    ...                                y_dot - a * sp.cos(theta) * theta_dot, 0), ("constraints[0]",))
    >>> import numpy as np
    >>> from nhham import contact_forces, numeric_model
    >>> model = numeric_model(sleigh, backend="numpy")
    >>> y = model.state(dict(x=0.0, y=0.0, theta=0.0, x_dot=1.0, y_dot=0.5, theta_dot=1.0))
    >>> forces = contact_forces(sleigh, [blade], y, model.multipliers(y))
    >>> print(np.round(forces.forces["blade"], 12) + 0.0)   # m y'' = 0.5 across the blade
    [[0.  0.5 0. ]]
    """
    Y = np.atleast_2d(np.asarray(states, dtype=float))
    lam = np.atleast_2d(np.asarray(multipliers, dtype=float))
    n, m = system.n, system.m
    if Y.shape[1] != 2 * n or lam.shape != (Y.shape[0], m):
        raise ValueError(f"contact_forces: states of shape (K, {2 * n}) and multipliers "
                         f"of shape (K, {m}) expected, got {Y.shape} and {lam.shape}")
    from nhham.numerics.codegen.contacts import contact_arrays

    values = {p.name: v for p, v in system.parameter_values.items()}
    values.update({str(k): float(v) for k, v in (parameters or {}).items()})  # str(symbol) is its name
    missing = [p.name for p in system.parameters if p.name not in values]
    if missing:
        from nhham.errors import MissingParameterValueError

        raise MissingParameterValueError(f"contact_forces: no value for {', '.join(missing)}")
    mu, maps = contact_arrays(system, contacts, Y, {p: values[p.name] for p in system.parameters})
    names, forces, residuals, ranks, warnings = [], {}, {}, {}, []
    for contact, (rows, J) in zip(contacts, maps):
        # Generalized force of the contact's constraints: -mu_c^T lambda_c, shape (K, n).
        Q = -np.einsum("kin,ki->kn", mu[:, rows, :], lam[:, rows])
        f = np.empty((len(Y), 3))
        res = np.zeros(len(Y))
        rank = 3
        for k in range(len(Y)):
            f[k], *_, sv = np.linalg.lstsq(J[k].T, Q[k], rcond=None)
            rank = min(rank, int(np.sum(sv > sv[0] * 1e-12)) if sv[0] > 0 else 0)
            size = np.linalg.norm(Q[k])
            if size > 0:
                res[k] = np.linalg.norm(J[k].T @ f[k] - Q[k]) / size
        names.append(contact.name)
        forces[contact.name], residuals[contact.name], ranks[contact.name] = f, res, rank
        if res.max(initial=0.0) > RESIDUAL_WARNING:
            carried = ", ".join(contact.constraints)
            warnings.append(f"contacts.{contact.name}: the constraints {carried} are not "
                            f"velocity conditions of the point (relative residual "
                            f"{res.max():.1e}): the force shown is the least-squares one")
        if rank < 3:
            warnings.append(f"contacts.{contact.name}: the point's velocity map has rank "
                            f"{rank} < 3: the force is determined only in its range")
    return ContactForces(tuple(names), forces, residuals, ranks, tuple(warnings))
