"""The two sides of a singular Lagrangian compared: Leg maps the Lagrangian final manifold
onto the Hamiltonian one and carries one motion to the other (Gotay–Nester).

The Lagrangian side is :func:`nhham.lagrangian.singular.lagrangian_chain` (on TQ, the SODE
built in), the Hamiltonian side the Dirac–Bergmann chain. Three checks:

* **into**: every final constraint chi of T*Q pulled back by Leg (p = dL/dv) vanishes on
  M_f^L (a decision of the engine each);
* **onto**: at seeded points x of M_f^L, Leg restricted to M_f^L has rank dim M_f^H (its
  Jacobian times a basis of T_x M_f^L): the image is open in M_f^H;
* **motions**: at the same points every Leg_*(X_L(x; a_free)) is a member of the family
  X_H(Leg x; u_free): the difference of the two at zero free multipliers and the pushed
  Lagrangian free directions lie in the span of the Hamiltonian ones (least-squares
  residuals, relative to the field's size). The converse is not asked point by point: a
  Hamiltonian free multiplier also chooses the velocities Leg forgets, which are
  coordinates of the point x on TQ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from nhham.errors import BudgetExceeded, NhhamError
from nhham.lagrangian.records import AlgorithmRun
from nhham.lagrangian.submanifold import Submanifold
from nhham.system.evaluation import numeric_function

__all__ = ["Equivalence", "equivalence"]

#: A residual relative to the field's size below this is agreement.
TOLERANCE = 1e-8


@dataclass(frozen=True)
class Equivalence:
    """The comparison of the two sides (frozen).

    Attributes
    ----------
    lagrangian : AlgorithmRun or None
        The chain on TQ (None when it could not run: ``why_not``).
    into : tuple of (str, Decision)
        Each Hamiltonian final constraint pulled back by Leg, vanishing on M_f^L.
    ranks : tuple of int
        The rank of Leg on T M_f^L at each point; ``expected`` = dim M_f^H.
    residual : float
        The largest relative residual of the motions' comparison.
    points : int
    """

    lagrangian: AlgorithmRun | None
    why_not: str | None
    into: tuple
    ranks: tuple
    expected: int | None
    residual: float
    points: int

    @property
    def agree(self) -> bool:
        return (self.why_not is None and all(d.value for _, d in self.into)
                and all(r == self.expected for r in self.ranks)
                and self.residual <= TOLERANCE)

    def to_dict(self) -> dict:
        run = self.lagrangian
        return {
            "agree": self.agree,
            "why_not": self.why_not,
            "lagrangian_status": None if run is None else run.status,
            "lagrangian_dimension": None if run is None else run.dimension,
            "lagrangian_constraints": [] if run is None else
            [{"label": lab, "constraint": str(c)}
             for lab, c in zip(run.final_labels, run.final_constraints)],
            "free_accelerations": [] if run is None else
            [s.name for s in run.free_multiplier_symbols if s.name.endswith("_ddot")],
            "into": [{"constraint": lab, **d.to_dict(value=True)} for lab, d in self.into],
            "ranks": list(self.ranks), "expected_rank": self.expected,
            "motion_residual": self.residual, "points": self.points,
        }


def equivalence(db) -> Equivalence:
    """Compare the Lagrangian chain with the Dirac–Bergmann chain ``db`` (module
    docstring). ``db`` must be consistent."""
    from nhham.lagrangian.singular import lagrangian_chain

    system = db.system
    if db.velocities_as_state:
        return Equivalence(None, "the chain on T*Q carries the velocities along ker W as "
                                 "state (a velocity constraint or a force nonlinear in them): "
                                 "the comparison through Leg is not built for it", (), (),
                           None, float("inf"), 0)
    try:
        run = lagrangian_chain(system, policy=db.policy)
        M = run.manifold
        if run.status == "inconsistent" or not isinstance(M, Submanifold):
            raise NhhamError(f"the chain on TQ is inconsistent: {run.inconsistency}")
        points, _ = M.points()
    except BudgetExceeded:
        raise
    except NhhamError as exc:
        return Equivalence(None, str(exc), (), (), None, float("inf"), 0)
    q, v = system.coordinates, system.velocities
    p = db.image.momenta
    momenta = [sp.diff(system.lagrangian, s) for s in v]
    to_leg = {pa: m for pa, m in zip(p, momenta)}
    into = tuple((lab, M.vanishes(sp.sympify(chi).xreplace(to_leg)))
                 for lab, chi in zip(db.run.final_labels, db.run.final_constraints))
    args = list(q) + list(v) + list(system.parameters)
    leg = numeric_function(args, momenta)
    jac = numeric_function(args, sp.Matrix(momenta).jacobian(list(q) + list(v)).tolist())
    t = system.time   # Leg depends on t: Leg_* X = dLeg X + (0, dp/dt)
    rate = numeric_function(args, [sp.diff(m, t) if t is not None else 0 for m in momenta])
    grads = numeric_function(args, sp.Matrix(run.final_constraints).jacobian(
        list(q) + list(v)).tolist()) if run.final_constraints else None
    lagrangian = _family(run, args)
    hamiltonian = _family(db.run, list(q) + list(p) + list(system.parameters))
    n, ranks, worst = len(q), [], 0.0
    for pt in points:
        x = [float(pt[s]) for s in list(q) + list(v)]
        par = [float(pt.get(s, 0.0)) for s in system.parameters]
        J = np.zeros((2 * n, 2 * n))
        J[:n, :n] = np.eye(n)
        J[n:, :] = np.asarray(jac(*x, *par), dtype=float)
        if grads is not None:
            G = np.asarray(grads(*x, *par), dtype=float)
            _, s, vt = np.linalg.svd(G)
            r = int(np.sum(s > 1e-9 * max(1.0, s[0] if s.size else 0.0)))
            T = vt[r:].T
        else:
            T = np.eye(2 * n)
        ranks.append(int(np.linalg.matrix_rank(J @ T, tol=1e-8 * max(1.0, np.abs(J).max()))))
        z = x[:n] + list(np.asarray(leg(*x, *par), dtype=float).ravel())
        L0, DL = lagrangian(x + par)
        H0, DH = hamiltonian(z + par)
        L0, DL = J @ L0, J @ DL
        L0[n:] += np.asarray(rate(*x, *par), dtype=float).ravel()
        scale = max(1.0, np.abs(H0).max(), np.abs(L0).max())
        # the Hamiltonian free directions also move along Leg's fibre (the velocities
        # Leg forgets are coordinates of TQ): only the Lagrangian family is checked in it
        worst = max(worst, _outside(L0 - H0, DH) / scale, _outside_all(DL, DH) / scale)
    return Equivalence(run, None, into, tuple(ranks), db.run.dimension, float(worst),
                       len(points))


def _family(run, args):
    """``at(values) -> (X0, D)``: the motions of ``run`` at a point of M_f, X0 + D c for
    every c. The multipliers solve every tangency row and condition of M_f at the point
    (least squares, no block chosen): a particular solution and the kernel's directions."""
    labels = list(run.final_labels) + [lab for lab, _ in run.field_conditions]
    A, b = run.rows(labels)
    Af, bf = numeric_function(args, A.tolist()), numeric_function(args, list(b))
    xi = numeric_function(args, list(run.base_field))
    Z = numeric_function(args, run.vertical_fields.tolist()) if run.vertical_fields.rows \
        else None

    def at(values):
        a = np.asarray(Af(*values), dtype=float).reshape(len(labels), -1)
        rhs = -np.asarray(bf(*values), dtype=float).ravel()
        base = np.asarray(xi(*values), dtype=float).ravel()
        if Z is None or a.shape[1] == 0:
            return base, np.zeros((base.size, 0))
        Zv = np.asarray(Z(*values), dtype=float)
        lam0, *_ = np.linalg.lstsq(a, rhs, rcond=None)
        _, s, vt = np.linalg.svd(a)
        r = int(np.sum(s > 1e-10 * max(1.0, s[0] if s.size else 0.0)))
        return base + Zv.T @ lam0, Zv.T @ vt[r:].T

    return at


def _outside(vector: np.ndarray, span: np.ndarray) -> float:
    """The norm of ``vector`` outside the column span of ``span``."""
    if span.size == 0 or not np.any(span):
        return float(np.abs(vector).max())
    coeffs, *_ = np.linalg.lstsq(span, vector, rcond=None)
    return float(np.abs(vector - span @ coeffs).max())


def _outside_all(columns: np.ndarray, span: np.ndarray) -> float:
    return max((_outside(columns[:, j], span) for j in range(columns.shape[1])), default=0.0)
