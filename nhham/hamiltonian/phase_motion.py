"""The motion of a singular Lagrangian on its final surface, as numbers.

Conventions (``DESIGN.md`` §2, "Singular Lagrangians"): the state is z = (q, p) on
M_f in T*Q; z' is the chain's motion with the multipliers it fixed
(:attr:`~nhham.hamiltonian.dirac_bergmann.DiracBergmann.motion`), so q' = dH_T/dp are the
velocities. A state given as (q, v) (``[initial]``, ``[steady]``) is carried to T*Q by
Leg, p = dL/dv. A chain that leaves a multiplier free has no motion to integrate until
gauge conditions chi(q) = 0 fix it (``[gauge]``: they join M_1, see
:func:`~nhham.hamiltonian.dirac_bergmann.dirac_bergmann`).

The linearisation at an equilibrium z* is exact: J = dz'/dz is differentiated
symbolically, and its restriction to T M_f = ker dPhi(z*) (Phi the final constraints) is
the state matrix, written in a chart of d = dim M_f phase coordinates (the rows of an
orthonormal basis T of T M_f that are best conditioned). Only derivatives along M_f
enter, where the motion (reduced on M_f) is the true one.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Callable

import numpy as np
import sympy as sp

from nhham.errors import InputError
from nhham.hamiltonian.dirac_bergmann import DiracBergmann, dirac_bergmann
from nhham.system.evaluation import numeric_function

__all__ = ["PhaseMotion", "PhaseLinearization", "phase_motion"]


@dataclass(frozen=True)
class PhaseLinearization:
    """The state matrix of the motion on M_f at an equilibrium z*.

    Attributes
    ----------
    chart : tuple of str
        The d phase coordinates of the chart (d = dim M_f).
    dependent : tuple of str
        The other 2n - d, functions of the chart's on M_f.
    matrix : ndarray, shape (d, d)
        A with delta z_chart' = A delta z_chart.
    tangent_matrix : ndarray, shape (d, d)
        The same map in an orthonormal basis of T M_f (better conditioned: its
        eigenvalues are reported).
    rank : int
        The rank of dPhi at z* (the chain's independent count where z* is regular).
    tangent_residual : float
        |J T - T A_T| / max(1, |J|) for the orthonormal basis T of T M_f: 0 up to rounding
        when the field is tangent to M_f at z* (a check of the chain's motion there).
    """

    chart: tuple
    dependent: tuple
    matrix: np.ndarray
    tangent_matrix: np.ndarray
    jacobian: np.ndarray
    rank: int
    tangent_residual: float


@dataclass(frozen=True, eq=False)
class PhaseMotion:
    """The determined motion z' = X(z) of a singular Lagrangian on M_f (frozen).

    Attributes
    ----------
    chain : DiracBergmann
        The chain (with the gauge conditions, if any) whose motion this is.
    names : tuple of str
        The phase coordinates: q, then p_q.
    labels : tuple of str
        The final constraints' labels (``primary[a]``, ``secondary[k]``, ``gauge[i]``...).

    Examples
    --------
    A Landau level, L = B x y' - k (x^2 + y^2)/2 with B = 2, k = 1: a rotation at k/B.

    >>> import numpy as np
    >>> from nhham import System
    >>> from nhham.hamiltonian.phase_motion import phase_motion
    >>> motion = phase_motion(System(["x", "y"], "B*x*y_dot - k*(x**2 + y**2)/2",
    ...                              parameters={"B": 2.0, "k": 1.0}))
    >>> motion.names
    ('x', 'y', 'p_x', 'p_y')
    >>> z = motion.state([1.0, 0.0], [0.0, 0.0])
    >>> z, motion.field(z) + 0.0      # y' = k x / B, x' = -k y / B
    (array([1., 0., 0., 2.]), array([0. , 0.5, 0. , 0. ]))
    >>> lin = motion.linearization(np.zeros(4))
    >>> lin.chart, lin.matrix.round(12) + 0.0
    (('x', 'y'), array([[ 0. , -0.5],
           [ 0.5,  0. ]]))
    """

    chain: DiracBergmann

    @property
    def n(self) -> int:
        return self.chain.n

    @cached_property
    def variables(self) -> tuple:
        """(q, p), and the velocities along ker W where the chain carries them as state."""
        return tuple(self.chain.variables)

    @property
    def names(self) -> tuple:
        return tuple(s.name for s in self.variables)

    @property
    def time(self):
        """t when L or the constraints depend on it (every function then takes it), else
        None."""
        return self.chain.system.time

    @cached_property
    def _args(self) -> tuple:
        return self.variables + ((self.time,) if self.time is not None else ())

    def _at(self, z, t) -> tuple:
        return (*z, t) if self.time is not None else tuple(z)

    @property
    def labels(self) -> tuple:
        return tuple(self.chain.run.final_labels)

    @cached_property
    def _field(self) -> Callable:
        return numeric_function(self._args, list(self.chain.motion), cse=True)

    @cached_property
    def _constraints(self) -> Callable:
        return numeric_function(self._args, list(self.chain.run.final_constraints))

    @cached_property
    def _constraint_jacobian(self) -> Callable:
        phi = sp.Matrix(list(self.chain.run.final_constraints))
        return numeric_function(self._args, phi.jacobian(self.variables))

    @cached_property
    def _jacobian(self) -> Callable:
        return numeric_function(self._args, self.chain.motion.jacobian(self.variables),
                                cse=True)

    @cached_property
    def _energy(self) -> Callable:
        return numeric_function(self._args, self.chain.image.canonical_hamiltonian)

    @cached_property
    def _momenta(self) -> Callable:
        s = self.chain.system
        p = [sp.diff(s.lagrangian, v) for v in s.velocities]
        return numeric_function(tuple(s.coordinates) + tuple(s.velocities)
                                + ((self.time,) if self.time is not None else ()), p)

    @property
    def does_work(self) -> bool:
        """Whether forces or the velocity constraints' reactions may do work (then H_c
        changes by it, :meth:`power`)."""
        return (self.chain.system.has_forces or bool(self.chain.system.constraints)
                or self.time is not None)

    @cached_property
    def _power(self) -> Callable:
        s, chain = self.chain.system, self.chain
        v = list(chain.motion[: self.n])
        at_v = dict(zip(s.velocities, v))
        P = sp.S.Zero
        if s.has_forces:
            P += sum((f * w for f, w in zip(s.generalized_forces.xreplace(at_v), v)), sp.S.Zero)
        # the reaction -lambda_i dphi_i/dv of each velocity constraint (no H_T term); their
        # multipliers follow the holonomic ones' (dirac_bergmann)
        h = len(s.holonomic)
        lam = chain.multipliers[h: h + len(s.constraints)]
        fixed = chain.fixed_multipliers
        for sym, c in zip(lam, s.constraints):
            mu = [sp.diff(c, w).xreplace(at_v) for w in s.velocities]
            P -= fixed.get(sym, sym) * sum((a * w for a, w in zip(mu, v)), sp.S.Zero)
        if self.time is not None:   # and dH_c/dt at fixed (q, p)
            P += sp.diff(chain.image.canonical_hamiltonian, self.time)
        return numeric_function(self._args, P)

    def power(self, z, t: float = 0.0) -> float:
        """dH_c/dt along the motion at z: (Q - lambda_i dphi_i/dv) . v with the velocities
        and multipliers of the motion (the primaries' and holonomic reactions do no work
        on M_f), plus dH_c/dt at fixed (q, p) with t in L; 0 when nothing does work."""
        return float(self._power(*self._at(z, t))) if self.does_work else 0.0

    def field(self, z, t: float = 0.0) -> np.ndarray:
        """z' at z (and t), shape (2n,)."""
        return np.asarray(self._field(*self._at(z, t)), dtype=float).reshape(-1)

    def constraints(self, z, t: float = 0.0) -> np.ndarray:
        """The final constraints at z (and t), shape (r,) in the order of :attr:`labels`."""
        if not self.labels:
            return np.zeros(0)
        return np.asarray(self._constraints(*self._at(z, t)), dtype=float).reshape(-1)

    def energy(self, z, t: float = 0.0) -> float:
        """H_c(z, t) (= E_L at the Legendre preimage on M_f)."""
        return float(self._energy(*self._at(z, t)))

    def velocities(self, z, t: float = 0.0) -> np.ndarray:
        """v = q' = dH_T/dp with the fixed multipliers, shape (n,)."""
        return self.field(z, t)[: self.n]

    @cached_property
    def _split(self) -> tuple:
        """(v_c, K) in (q, p): v = v_c + K u, v_c = dH_c/dp, K's columns dphi_a/dp."""
        chain = self.chain
        qp = tuple(chain.algebra.variables) + ((self.time,) if self.time is not None else ())
        momenta = chain.image.momenta
        vc = [sp.diff(chain.image.canonical_hamiltonian, pa) for pa in momenta]
        K = [[sp.diff(phi, pa) for phi in chain.image.constraints] for pa in momenta]
        return numeric_function(qp, vc), numeric_function(qp, K)

    def state(self, q, v, t: float = 0.0) -> np.ndarray:
        """z = Leg(q, v) = (q, dL/dv) (at t), shape (2n,); with the velocities along ker W
        as state, their u^a too (v - dH_c/dp = u^a dphi_a/dp, least squares), (2n + r,)."""
        q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
        p = np.asarray(self._momenta(*self._at([*q, *v], t)), dtype=float).reshape(-1)
        z = np.concatenate([q, p])
        if not self.chain.velocities_as_state:
            return z
        vc_f, K_f = self._split
        vc = np.asarray(vc_f(*self._at(z, t)), dtype=float).reshape(-1)
        K = np.asarray(K_f(*self._at(z, t)), dtype=float).reshape(self.n, -1)
        u = np.linalg.lstsq(K, v - vc, rcond=None)[0]
        return np.concatenate([z, u])

    def require_autonomous(self) -> None:
        """Raise InputError (key ``steady``) with t in L: no steady state to linearise."""
        if self.time is not None:
            raise InputError("steady: a singular Lagrangian with t has no steady state to "
                             "linearise about (its motion depends on t)", key="steady")

    def linearization(self, z) -> PhaseLinearization:
        """The state matrix on M_f at the equilibrium z (see the module docstring).

        Raises
        ------
        InputError
            With t in L (no equilibrium is a point of T*Q for all t), key ``steady``.
        """
        self.require_autonomous()
        z = np.asarray(z, dtype=float)
        J = np.atleast_2d(np.asarray(self._jacobian(*z), dtype=float))
        N = 2 * self.n
        if self.labels:
            G = np.atleast_2d(np.asarray(self._constraint_jacobian(*z), dtype=float))
            _, s, Vt = np.linalg.svd(G)
            rank = int(np.sum(s > 1e-10 * max(1.0, s[0] if s.size else 0.0)))
            T = Vt[rank:].T
        else:
            rank, T = 0, np.eye(N)
        A_T = T.T @ J @ T
        residual = float(np.linalg.norm(J @ T - T @ A_T) / max(1.0, float(np.linalg.norm(J))))
        chart = _chart(T)
        Ts = T[chart]
        A = Ts @ A_T @ np.linalg.inv(Ts) if T.shape[1] else np.zeros((0, 0))
        names = self.names
        return PhaseLinearization(
            chart=tuple(names[i] for i in chart),
            dependent=tuple(nm for i, nm in enumerate(names) if i not in set(chart)),
            matrix=A, tangent_matrix=A_T, jacobian=J, rank=rank, tangent_residual=residual)


def _chart(T, floor: float = 1e-3) -> list:
    """d rows of the orthonormal T (2n x d), the coordinates first, then the momenta: a
    row is taken when it adds a direction of size above ``floor`` (readable charts: x, y
    for a Landau level rather than y, p_x)."""
    d = T.shape[1]
    chosen: list = []
    for i in range(T.shape[0]):
        if len(chosen) == d:
            break
        trial = T[chosen + [i]]
        if np.linalg.svd(trial, compute_uv=False)[-1] > floor:
            chosen.append(i)
    if len(chosen) < d:  # no such rows in order: the best conditioned ones
        from scipy.linalg import qr

        chosen = sorted(qr(T.T, pivoting=True)[2][:d].tolist())
    return chosen


def phase_motion(system, *, gauge=(), policy=None) -> PhaseMotion:
    """The determined motion of ``system``'s singular Lagrangian on M_f.

    Parameters
    ----------
    system : nhham.System
        A singular Lagrangian (at its parameter values, as the chain runs it).
    gauge : sequence of sympy.Expr, optional
        Gauge conditions chi(q) = 0 fixing the multipliers the chain leaves free.
    policy : Policy, optional

    Returns
    -------
    PhaseMotion

    Raises
    ------
    InputError
        The chain is inconsistent (key ``lagrangian``), or it leaves multipliers free
        (key ``gauge``: naming them, and the gauge conditions already given).

    Examples
    --------
    Christ-Lee in the plane leaves the multiplier of p_xi free; the gauge xi = 0, x2 = 0
    fixes it and makes the four final constraints second class.

    >>> import sympy as sp
    >>> from nhham import System, phase_motion
    >>> system = System(["x1", "x2", "xi"], "((x1_dot + xi*x2)**2 + (x2_dot - xi*x1)**2)/2")
    >>> motion = phase_motion(system, gauge=[sp.Symbol("xi"), sp.Symbol("x2")])
    >>> motion.labels, motion.chain.second_class
    (('primary[0]', 'gauge[0]', 'gauge[1]', 'secondary[0]'), 4)
    """
    chain = dirac_bergmann(system, policy=policy, gauge=tuple(gauge))
    if not chain.consistent:
        raise InputError(f"lagrangian: the Dirac-Bergmann chain is inconsistent "
                         f"({chain.run.inconsistency}): there is no motion",
                         key="lagrangian")
    free = chain.run.free_multiplier_symbols
    if free:
        names = ", ".join(s.name for s in free)
        given = (f"the gauge conditions {', '.join(str(c) for c in chain.gauge)} leave "
                 f"{names} free" if chain.gauge else
                 f"the multipliers {names} are free (first-class constraints: gauge freedom)")
        raise InputError(f"gauge: {given}; give conditions chi(q) = 0 that fix them in "
                         f"[gauge] (conditions = [...]; nhham classify lists the first-class "
                         f"constraints and their gauge generators)", key="gauge")
    return PhaseMotion(chain)
