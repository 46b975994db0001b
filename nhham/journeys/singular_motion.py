"""``simulate`` and ``linearize`` of a singular Lagrangian: the chain's motion on M_f.

The state is z = (q, p) on the final surface M_f of the Dirac–Bergmann chain
(:mod:`nhham.hamiltonian.phase_motion`); the scene's ``[initial]`` and ``[steady]`` give
(q, v), carried to T*Q by Leg and checked on M_f; ``[gauge]`` conditions fix the
multipliers a gauge system leaves free. The run is scipy's ``solve_ivp`` with one of the
adaptive methods of :data:`nhham.numerics.methods.METHODS` (those with a ``scipy`` loop);
the constraints of M_f and H_c are measured along it, not imposed.
"""

from __future__ import annotations

import functools
import time
from typing import Mapping

import numpy as np

from nhham.errors import InputError
from nhham.journeys.answer import Answer, capture_warnings, quiet_steps

__all__ = ["simulate_singular", "linearize_singular", "ON_SURFACE"]

#: A given state is on M_f when every final constraint is at most this times
#: max(1, |z|) there (the values of [initial] are decimals of exact ones).
ON_SURFACE = 1e-9

_RUN_OPTIONS = ("rtol", "atol", "max_step", "t_eval")


def _motion(scene, steps):
    from nhham.hamiltonian.phase_motion import phase_motion

    gauge = tuple(scene.gauge)   # an UnreadTable raises its problems here
    with steps.step("Dirac-Bergmann chain and its motion on M_f"
                    + (f" (gauge: {len(gauge)} conditions)" if gauge else "")):
        motion = phase_motion(scene.system, gauge=gauge)
    return motion


def phase_state(motion, values: Mapping, table: str) -> tuple:
    """(z on M_f, warnings) from a table of coordinates and velocities (``[initial]``,
    ``[steady]``): z = Leg(q, v), checked on M_f.

    Raises
    ------
    InputError
        A coordinate missing that the final constraints do not determine, a velocity
        missing that p depends on, or a state off M_f (naming each final constraint's
        residual), key ``table``.
    """
    system = motion.chain.system
    names = [q.name for q in system.coordinates]
    momenta = [system.lagrangian.diff(w) for w in system.velocities]
    needed = {v.name for v in system.velocities if any(p.has(v) for p in momenta)}
    absent = sorted(needed - set(values))
    if absent:
        raise InputError(f"{table}: no value for {', '.join(absent)} (the momenta dL/dv "
                         f"depend on it)", key=table)
    v_given = [float(values.get(s.name, 0.0)) for s in system.velocities]
    z, solved = _completed(motion, values, names, v_given, table)
    residual = motion.constraints(z)
    scale = max(1.0, float(np.max(np.abs(z))) if z.size else 1.0)
    off = [(lab, r) for lab, r in zip(motion.labels, residual)
           if not abs(r) <= ON_SURFACE * scale]
    if off:
        listed = ", ".join(f"{lab} = {r:.3g}" for lab, r in off)
        raise InputError(f"{table}: the state is not on the final surface M_f of the chain "
                         f"(at p = dL/dv: {listed}); nhham classify lists its constraints",
                         key=table)
    warnings = [f"{table}: solved from the final constraints: "
                + ", ".join(f"{nm} = {z[names.index(nm)]:.10g}" for nm in solved)] if solved else []
    v_motion = motion.velocities(z)
    for s, given, moved in zip(system.velocities, v_given, v_motion):
        if s.name in values and abs(given - moved) > 1e-9 * max(1.0, abs(moved)):
            warnings.append(f"{table}: {s.name} = {given:.10g} given; the motion on M_f has "
                            f"{s.name} = {moved:.10g} there (a singular L: p does not fix "
                            f"it), and the run uses the motion's")
    return z, warnings


def _completed(motion, values, names, v, table) -> tuple:
    """(z = Leg(q, v), the coordinates solved): the coordinates ``values`` leaves out (a
    multiplier written as a coordinate: the pendulum's tension) solved from the final
    constraints by least squares from 0, kept only where the residual vanishes and the
    solution is isolated (the Jacobian in them of full column rank)."""
    from scipy.optimize import least_squares

    missing = [i for i, nm in enumerate(names) if nm not in values]
    q = np.array([float(values[nm]) if nm in values else 0.0 for nm in names])
    if not missing:
        return motion.state(q, v), ()

    def residual(u):
        q[missing] = u
        return motion.constraints(motion.state(q, v))

    listed = ", ".join(names[i] for i in missing)
    if not motion.labels:
        raise InputError(f"{table}: no value for {listed}", key=table)
    fit = least_squares(residual, np.zeros(len(missing)), xtol=1e-15, ftol=1e-15, gtol=1e-15)
    rank = np.linalg.matrix_rank(fit.jac) if fit.jac.size else 0
    if not np.max(np.abs(fit.fun), initial=0.0) <= 1e-12 or rank < len(missing):
        raise InputError(f"{table}: no value for {listed}, and the final constraints do not "
                         f"determine {'it' if len(missing) == 1 else 'them'} there", key=table)
    q[missing] = fit.x
    return motion.state(q, v), tuple(names[i] for i in missing)


def simulate_singular(scene, *, t_end: float | None = None, options: Mapping | None = None,
                      steps=None) -> Answer:
    """A run of a singular Lagrangian's motion on M_f (``nhham simulate``).

    Parameters
    ----------
    scene : Scene
        A singular Lagrangian with an ``[initial]`` table (and ``[gauge]`` where the chain
        leaves multipliers free).
    t_end : float, optional
        Default: the scene's ``[simulate]`` table, else 10.
    options : mapping, optional
        ``method`` (an adaptive method), ``rtol``, ``atol``, ``max_step``, ``t_eval``.
    steps : Steps, optional

    Returns
    -------
    Answer
        ``data``: the ``result`` of ``nhham simulate --json`` (the state is (q, p); the
        ``singular`` key: final constraints, gauge, first-class count, final velocities).

    Examples
    --------
    A Landau level rotates at k/B: after t = pi the charge at (1, 0) is at (0, 1).

    >>> from nhham import loads_scene
    >>> from nhham.journeys.singular_motion import simulate_singular
    >>> scene = loads_scene('''
    ... coordinates = ["x", "y"]
    ... parameters = { B = 2.0, k = 1.0 }
    ... lagrangian = "B*x*y_dot - k*(x**2 + y**2)/2"
    ... [initial]
    ... x = 1.0
    ... y = 0.0
    ... ''', check_initial=False)
    >>> answer = simulate_singular(scene, t_end=3.141592653589793)
    >>> answer.data["state"], [round(y, 8) + 0.0 for y in answer.data["y_final"]]
    (['x', 'y', 'p_x', 'p_y'], [0.0, 1.0, 0.0, 0.0])
    """
    from scipy.integrate import solve_ivp

    from nhham.numerics.methods import DEFAULT_METHOD, METHODS, lookup
    from nhham.numerics.run import report_progress
    from nhham.render.singular_motion import (run_arrays, singular_simulate_data,
                                              singular_simulate_text)

    steps = quiet_steps(steps)
    opts = dict(options or {})
    # the chain's motion runs the adaptive methods only: auto is DOP853 there
    chosen = opts.pop("method", DEFAULT_METHOD)
    method = lookup(DEFAULT_METHOD if chosen == "auto" else chosen, key="simulate.method")
    if "scipy" not in method.loops:
        usable = ", ".join(m.name for m in METHODS.values() if "scipy" in m.loops)
        raise InputError(f"simulate.method: {method.name} does not integrate a singular "
                         f"Lagrangian (its step needs W invertible); these do: {usable}",
                         key="simulate.method")
    unused = sorted(set(opts) - set(_RUN_OPTIONS))
    if unused:
        raise InputError(f"simulate.{unused[0]}: not used by the run of a singular Lagrangian "
                         f"(it takes {', '.join(_RUN_OPTIONS)})", key=f"simulate.{unused[0]}")
    t_end = float(t_end if t_end is not None else (scene.simulate.t_end or 10.0))
    motion = _motion(scene, steps)
    if scene.initial_given is None:
        raise InputError("initial: simulate needs an [initial] table", key="initial")
    given = scene.initial_given.given   # an UnreadTable raises its problems here
    values = {k: float(v.evalf(subs={s: scene.system.parameter_values[s]
                                     for s in v.free_symbols
                                     if s in scene.system.parameter_values}))
              for k, v in given.items()}
    z0, warnings = phase_state(motion, values, "initial")
    rtol, atol = float(opts.get("rtol", 1e-9)), float(opts.get("atol", 1e-12))
    run: dict = dict(rtol=rtol, atol=atol, max_step=float(opts.get("max_step", np.inf)))
    if opts.get("t_eval") is not None:
        run["t_eval"] = np.asarray(opts["t_eval"], dtype=float)
    start = time.perf_counter()
    reported = [0]

    def rhs(t, y):
        if steps.progress and time.perf_counter() - start > 1.0:   # a long run says so
            reported[0] = report_progress(t, 0.0, t_end, reported[0])
        # the work W' = (Q - lambda dphi/dv) . v rides along: H_c(t) - H_c(0) = W(t)
        if motion.does_work:
            return np.append(motion.field(y[:-1], t), motion.power(y[:-1], t))
        return motion.field(y, t)

    with capture_warnings() as caught:
        with steps.step(f"simulate the motion on M_f with {method.name}"):
            sol = solve_ivp(rhs, (0.0, t_end), np.append(z0, 0.0) if motion.does_work else z0,
                            method=method.load(), **run)
            wall = time.perf_counter() - start
    data = singular_simulate_data(motion, sol, method.name, (0.0, t_end), wall,
                                  dict(run, method=method.name))
    failure = None
    if not sol.success:
        failure = (f"{method.name} stopped at t = {data['t_final']:.10g}: {sol.message}; try "
                   f"another method (--method Radau) or smaller tolerances")
    title = scene.name or str(scene.source)

    def save(path) -> str:
        """The run written as ``nhham simulate --output`` writes one (t, q, p, H_c)."""
        from nhham.numerics.storage import save_states

        Z, work, energy = run_arrays(motion, sol)
        return save_states(path, sol.t, Z, motion.names, energy, work)

    return Answer("simulate", data, functools.partial(singular_simulate_text, title, data),
                  warnings=tuple(warnings) + tuple(caught), failure=failure,
                  payload={"solution": sol, "motion": motion, "save": save},
                  system=scene.system)


def linearize_singular(scene, *, steps=None) -> Answer:
    """The state matrix of a singular Lagrangian's motion on M_f at its ``[steady]``
    equilibrium (``nhham linearize``).

    Returns
    -------
    Answer
        ``data``: the ``result`` of ``nhham linearize --json``: the chart (d phase
        coordinates), the state matrix, eigenvalues and verdict, the ``singular`` key.

    Raises
    ------
    InputError
        No ``[steady]``, a state off M_f or not at rest there (z' != 0: the relative
        equilibria of a singular L are not built), or free multipliers without ``[gauge]``.

    Examples
    --------
    An inductor-capacitor loop in charges oscillates at omega^2 = 1/(ell C):

    >>> from nhham import loads_scene
    >>> from nhham.journeys.singular_motion import linearize_singular
    >>> scene = loads_scene('''
    ... coordinates = ["qL", "qC"]
    ... parameters = { ell = 1.0, Cap = 4.0 }
    ... lagrangian = "ell*qL_dot**2/2 - qC**2/(2*Cap)"
    ... constraints = ["qL_dot - qC_dot"]
    ... [steady]
    ... qL = 0.0
    ... qC = 0.0
    ... qL_dot = 0.0
    ... qC_dot = 0.0
    ... ''')
    >>> answer = linearize_singular(scene)
    >>> sorted(round(im, 12) + 0.0 for re, im in answer.data["eigenvalues"])
    [-0.5, 0.0, 0.5]

    (0: q_L - q_C is conserved by the current law, a line of equilibria.)
    """
    from nhham.numerics.linearization import linearization_result
    from nhham.numerics.spectra import spectra
    from nhham.render.singular_motion import singular_linearize_data, singular_linearize_text

    steps = quiet_steps(steps)
    if scene.steady is None:
        raise InputError("steady: linearize needs a [steady] table (an equilibrium: a value "
                         "for every coordinate and velocity)", key="steady")
    motion = _motion(scene, steps)
    motion.require_autonomous()   # before the [steady] checks: their messages assume none
    params = {s.name: v for s, v in scene.system.parameter_values.items()}
    values = scene.steady.values(params)
    z, warnings = phase_state(motion, values, "steady")
    rate = motion.field(z)
    scale = max(1.0, float(np.max(np.abs(z))))
    if not np.all(np.abs(rate) <= 1e-9 * scale):
        moving = ", ".join(f"{n}' = {r:.3g}" for n, r in zip(motion.names, rate)
                           if abs(r) > 1e-9 * scale)
        raise InputError(f"steady: not an equilibrium of the motion on M_f ({moving}); "
                         f"linearize takes a singular Lagrangian at rest (its relative "
                         f"equilibria are not built)", key="steady")
    with steps.step("linearise on M_f (exact Jacobian)"):
        phase = motion.linearization(z)
        # eigenvalues of the orthonormal form (better conditioned than the chart's)
        ev, margins, tol, _ = spectra(phase.tangent_matrix[None])
        lin = linearization_result(
            phase.matrix, phase.chart, "symbolic",
            "float64, the exact Jacobian of the motion restricted to T M_f, LAPACK "
            "eigenvalues", phase.chart, phase.jacobian, (), phase.dependent,
            dict(zip(motion.names, (float(x) for x in z))),
            dict(zip(motion.labels, (float(r) for r in motion.constraints(z)))),
            float(np.max(np.abs(rate), initial=0.0)), tol=float(tol[0]),
            eigenvalues=ev[0], margins=margins[0])
    expected = len(motion.variables) - int(motion.chain.run.dimension or 0)
    if phase.rank != expected:
        warnings.append(f"steady: the final constraints have rank {phase.rank} there, "
                        f"{expected} on M_f generically: the point is singular on M_f and "
                        f"the linearisation may not describe it")
    if phase.tangent_residual > 1e-12:
        warnings.append(f"steady: the motion is not tangent to M_f there (|J T - T A| = "
                        f"{phase.tangent_residual:.1e} relative): the state matrix is not "
                        f"trustworthy")
    data = singular_linearize_data(scene, lin, motion, phase)
    title = scene.name or str(scene.source)
    return Answer("linearize", data,
                  functools.partial(singular_linearize_text, title, scene, lin, data),
                  warnings=tuple(warnings),
                  payload={"linearization": lin, "phase": phase, "motion": motion},
                  system=scene.system)
