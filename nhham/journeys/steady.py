"""The ``[steady]`` motion of a scene linearised: at its parameter values
(:func:`steady_linearization`, what ``nhham linearize`` answers), and at many parameter
points in one reference chart (:func:`sweep_reference` at probes, :func:`steady_batch`),
which a study's points and ``nhham linearize --sweep`` both take
(:mod:`nhham.journeys.stability`, :mod:`nhham.study.stability`).
"""

from __future__ import annotations

import warnings

import numpy as np

from nhham.errors import InputError
from nhham.lagrangian.jacobian import EXACT_DIGITS
from nhham.numerics.quotient import MOMENTUM, ORBIT

__all__ = ["steady_linearization", "steady_states", "law_mismatch", "sweep_reference",
           "steady_batch", "LAW_TOL", "EXACT_MAX_N"]

#: Relative distance of a ``[control]`` law's value from its input's ``[steady]`` value
#: above which the motion is not a steady motion of the closed loop (one point and many).
LAW_TOL = 1e-9

#: Largest number of coordinates for which ``auto`` uses the exact Jacobian.
EXACT_MAX_N = 4


def steady_linearization(scene, system, model, method: str = "auto", independent=None,
                         generator=None):
    """The linearisation of ``system`` (``model``) about the scene's ``[steady]`` motion at
    the model's parameter values: its ``[control]`` laws checked there, the forces
    checked to be defined, the dependent coordinates and velocities solved, and the
    Jacobian exact where ``method`` says (``auto``: n <= :data:`EXACT_MAX_N`).

    Parameters
    ----------
    scene : Scene
    system : System
        ``scene.steady_system()`` (the closed loop) or ``scene.system`` (the open loop).
    model : NumericModel
        Of ``system``, at the parameter values wanted.
    method : {"auto", "exact", "complex-step"}
    independent : sequence of str, optional
        The chart (default: chosen at the state).
    generator : nhham.numerics.relative.Generator, optional
        The scene's checked ``[symmetry]`` (:func:`symmetry_generator`): a motion along
        it is linearised in co-moving variables (the complex-step Jacobian of X - w Xi).

    Returns
    -------
    Linearization
    """
    from nhham.numerics.linearization import linearize
    from nhham.numerics.steady_sweep import steady_state
    from nhham.system.force_checks import check_forces_at

    values = scene.steady.values(model.parameters)
    _check_laws_at(scene, system, model, values)
    check_forces_at(system, values, where="the [steady] motion")
    model, state = steady_state(model, values, independent)
    lin = linearize(model, state, family=scene.steady.family(model.parameters),
                    independent=independent, generator=generator)
    turning = lin.relative is not None and lin.relative["turning"]
    if turning and method == "exact":
        raise InputError("method exact (--exact): the [steady] motion is a relative "
                         "equilibrium (it moves along the [symmetry] generator), whose state "
                         "matrix (of X - w Xi) is formed by the complex step only; leave the "
                         "method to auto or use --numeric", key="method")
    level = MOMENTUM in lin.neutral
    if level and method == "exact":
        raise InputError("method exact (--exact): the [symmetry]'s momentum is conserved and "
                         "its level is divided out, whose differential on M_1 is formed by the "
                         "complex step only; leave the method to auto or use --numeric",
                         key="method")
    if not (turning or level) and (method == "exact"
                                   or (method == "auto" and system.n <= EXACT_MAX_N)):
        lin = _exact(scene, system, model, lin)
    return lin


def _check_laws_at(scene, system, model, values) -> None:
    """Each [control] law closed in ``system`` gives its input's [steady] value (when the
    table gives one) at the steady state: else the motion is not one of the closed loop."""
    import sympy as sp

    closed = {u: law for u, law in scene.control.items() if u not in model.input_names
              and u in values}
    if not closed or system is scene.system:
        return
    point = {sp.Symbol(k): sp.Float(v) for k, v in {**model.parameters, **values}.items()}
    for u, law in sorted(closed.items()):
        value = complex(sp.sympify(law).xreplace(point).evalf())
        want = values[u]
        if abs(value - want) > LAW_TOL * max(1.0, abs(want)):
            raise InputError(f"control.{u}: the law gives {value.real:.10g} at the [steady] "
                             f"motion, where [steady] gives {u} = {want:.10g}: the motion is "
                             f"not a steady motion of the closed loop", key="control")


def _exact(scene, system, model, lin):
    """The same linearisation with the exact Jacobian in the numeric chart."""
    import mpmath
    import numpy as np
    import sympy as sp

    from nhham.lagrangian.jacobian import exact_jacobian, exact_number
    from nhham.numerics.linearization import linearization_result

    # the model's values (a model passed in with other values than the scene's)
    params = {p.name: exact_number(model.parameters.get(p.name, v))
              for p, v in system.parameter_values.items()}
    params.update({u: exact_number(model.parameters[u]) for u in model.input_names})
    point = {sp.Symbol(k): v for k, v in params.items()}
    state = {}
    for name, expr in scene.steady.expressions.items():
        if name not in model.names:   # an input's steady value
            continue
        value = sp.sympify(expr).xreplace(point)
        state[name] = value if value.is_number else exact_number(float(value.evalf()))
    ej = exact_jacobian(system, state, params, lin.chart)
    keep = [i for i, s in enumerate(ej.chart) if s not in lin.neutral]
    A = ej.matrix.extract(keep, keep)
    names = [ej.chart[i] for i in keep]
    done: list = []   # the quotients taken: (names then, pivot, vector)
    for label in lin.neutral:
        if label == ORBIT:   # Xi(y0) in the chart, exactly
            v = _exact_orbit(scene, system, state, point, done[0][0] if done else names)
        elif label.startswith("d/d"):   # a tangent of the steady family
            p = sp.Symbol(label[3:])
            v = [sp.diff(scene.steady.expressions[s], p).xreplace(point)
                 for s in done[0][0]] if done else \
                [sp.diff(scene.steady.expressions[s], p).xreplace(point) for s in names]
            if done:   # the original variables: carried into the quotient below
                v = dict(zip(done[0][0], v))
        else:
            continue
        if isinstance(v, dict):   # its class in the quotients taken before
            for before, j, t in done:
                w = [v[s] for s in before]
                w = [w[i] - w[j] / t[j] * t[i] for i in range(len(before))]
                v = {s: w[i] for i, s in enumerate(before) if i != j}
            v = [v[s] for s in names]
        t = sp.Matrix(v)
        j = max(range(len(names)), key=lambda i: abs(float(t[i])))
        T = sp.eye(len(names))
        T[:, j] = t
        B = T.LUsolve(A * T)
        rest = [i for i in range(len(names)) if i != j]
        done.append((list(names), j, list(t)))
        A, names = B.extract(rest, rest), [names[i] for i in rest]
    with mpmath.workdps(EXACT_DIGITS + 10):
        M = mpmath.matrix([[mpmath.mpmathify(sp.N(e, EXACT_DIGITS + 10)) for e in A.row(i)]
                           for i in range(A.rows)]) if A.rows else None
        ev = []
        if A.rows:
            E = mpmath.eig(M, left=False, right=False)
            # mpmath returns (E, ER, EL) for a 1 x 1 matrix
            ev = [complex(z) for z in (E[0] if isinstance(E, tuple) else E)]
    Af = np.array([[float(sp.N(e, 20)) for e in A.row(i)] for i in range(A.rows)]).reshape(
        A.rows, A.rows)
    scale = max(1.0, float(np.abs(Af).max(initial=0.0)))
    return linearization_result(
        Af, tuple(names), "exact",
        f"exact symbolic Jacobian (implicit differentiation of the saddle-point system, "
        f"exact arithmetic on the parameter values as decimals), eigenvalues by mpmath at "
        f"{EXACT_DIGITS} digits", ej.chart,
        np.array([[float(sp.N(e, 20)) for e in ej.matrix.row(i)] for i in range(ej.matrix.rows)]),
        lin.neutral, lin.dependent, dict(lin.state), dict(lin.residuals),
        lin.acceleration_residual, tol=10.0 ** (-EXACT_DIGITS + 5) * scale, eigenvalues=ev,
        exact_matrix=A, inputs=lin.inputs, B=lin.input_matrix,
        relative=None if lin.relative is None else dict(lin.relative),
        kkt=(lin.kkt_solve, lin.kkt_ratio), implied=lin.implied)


def _exact_orbit(scene, system, state, point, names):
    """The [symmetry]'s orbit direction Xi(y0) = (xi(q0), D xi(q0) v0), exactly, as a
    mapping from the chart variables (of the chart before any quotient) to its
    components."""
    import sympy as sp

    q = system.coordinates
    xi = [e.xreplace(point) for e in scene.symmetry.field(q)]
    at = {sp.Symbol(k): v for k, v in state.items()}
    components = {}
    for A, qa in enumerate(q):
        components[qa.name] = xi[A].xreplace(at)
        components[system.velocities[A].name] = sum(
            (sp.diff(xi[A], qb) * system.velocities[B] for B, qb in enumerate(q)),
            sp.S.Zero).xreplace(at)
    return {s: components[s] for s in names}


def steady_states(scene, model, points) -> tuple:
    """The ``[steady]`` states at many parameter points, as a study linearises them.

    Parameters
    ----------
    scene : Scene
    model : NumericModel
        Of ``scene.steady_system()``.
    points : mapping of str to ndarray, shape (N,)
        Swept parameter -> its values (the others at the model's values).

    Returns
    -------
    (Y, P, bad, missed)
        ``Y`` (N, 2n) the steady states, ``P`` (N, parameters) every parameter's value
        (inputs at their ``[steady]`` values), ``bad`` (N,) where an entry of ``[steady]``
        is not a finite real number, ``missed`` (N,) where a ``[control]`` law does not
        give its input's ``[steady]`` value (:func:`law_mismatch`): no steady motion of the
        closed loop there, which ``nhham linearize`` refuses.
    """
    names = model.parameter_names
    N = len(next(iter(points.values()))) if points else 1
    P = np.tile(np.asarray(model.parameter_values, dtype=float), (N, 1))
    for k, v in points.items():
        P[:, names.index(k)] = v
    params = {k: P[:, i] for i, k in enumerate(names)}
    steady = scene.steady.arrays(params)
    for u in model.input_names:
        if u in steady:
            P[:, names.index(u)] = steady[u]
    Y = np.column_stack([steady[s] for s in model.names])
    bad = ~np.isfinite(Y).all(axis=1) | ~np.isfinite(P).all(axis=1)
    missed = law_mismatch(scene, model, Y, P, steady) & ~bad
    Y[bad] = 0.0
    P[bad] = np.where(np.isfinite(P[bad]), P[bad], 0.0)
    return Y, P, bad, missed


def sweep_reference(scene, system, model, points, generator=None) -> tuple:
    """The chart and the neutral directions of a sweep or a study, decided once: the
    command's linearisation (its laws and forces checked, complex-step) at each probe
    point, the first's chart, the directions neutral at every probe
    (:func:`~nhham.numerics.steady_sweep.common_reference`).

    Parameters
    ----------
    scene : Scene
    system : System
        ``scene.steady_system()``.
    model : NumericModel
        Of ``system``.
    points : sequence of mappings
        The probes' parameter values (``{name: value}``).
    generator : Generator, optional
        The scene's checked ``[symmetry]``.

    Returns
    -------
    (ChartChoice, list of str)
        The reference and the probes where the command refused (their messages).

    Raises
    ------
    InputError
        (key ``steady``) no probe linearises.
    """
    from nhham.errors import ComputationError
    from nhham.numerics.linearization import linearize as at_state
    from nhham.numerics.steady_sweep import common_reference

    found: list = []
    problems: list = []
    for params in points:
        m = model.with_parameters(**params)
        try:
            # the command's linearisation there (laws and forces checked), numerically
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")   # a probe's notes are not the sweep's
                lin = steady_linearization(scene, system, m, "complex-step",
                                           found[0][2].chart if found else None,
                                           generator=generator)
            found.append((m, scene.steady.family(m.parameters), lin))
        except (InputError, ComputationError) as exc:
            problems.append(f"at {params}: {exc}")
    if not found:
        raise InputError("linearize: the [steady] motion is not steady (or not on M_1) at "
                         "any probe point: " + "; ".join(problems), key="steady")
    m, family, first = found[0]
    state = np.array([first.state[name] for name in m.names])

    def relinearize(neutral, keep):
        return at_state(m, state, independent=first.chart, neutral=neutral,
                        family={p: t for p, t in (family or {}).items() if p in keep} or None,
                        generator=generator)

    return common_reference([lin for _, _, lin in found], relinearize), problems


def steady_batch(scene, model, choice, points, generator=None, build: bool = True) -> tuple:
    """The linearisations of the ``[steady]`` motion at many parameter points in the
    reference's chart, as a study and a sweep take them.

    Parameters
    ----------
    scene : Scene
    model : NumericModel
        Of ``scene.steady_system()``.
    choice : ChartChoice
        The reference (:func:`sweep_reference`).
    points : mapping of str to ndarray, shape (N,)
        Swept parameter -> its values.
    generator : Generator, optional
    build : bool, optional
        Compile the complex kernels now if the compile cache has none (a study's
        thousands of points; a command's sweep evaluates them by numpy until then: the
        same expressions).

    Returns
    -------
    (LinearizationBatch, ndarray of bool)
        The batch, its ``status`` 1 where an entry of ``[steady]`` is not a finite number
        and 2 where a ``[control]`` law misses its input's steady value (the command
        refuses both); and that mask.
    """
    from dataclasses import replace

    from nhham.numerics.batch_linearization import linearize_batch

    Y, P, bad, missed = steady_states(scene, model, points)
    families = None
    if any(s.startswith("d/d") for s in choice.neutral):
        families = [scene.steady.family(dict(zip(model.parameter_names, p))) for p in P]
    batch = linearize_batch(model, Y, P, reference=choice, families=families,
                            generator=generator, build=build)
    status = batch.status.copy()
    status[bad] = 1
    status[missed] = 2   # not a steady motion of the closed loop: the command refuses it
    out = bad | missed
    verdicts = np.where(out, -1, batch.verdicts).astype(np.int8)
    return replace(batch, status=status, verdicts=verdicts), out


def law_mismatch(scene, model, Y, P, steady) -> np.ndarray:
    """Where a ``[control]`` law closed in ``model`` does not give its input's ``[steady]``
    value (relative :data:`LAW_TOL`, as :func:`steady_linearization` checks one point).

    Parameters
    ----------
    Y : ndarray, shape (N, 2n)
    P : ndarray, shape (N, parameters)
    steady : mapping of str to ndarray, shape (N,)
        The ``[steady]`` entries at the points.

    Returns
    -------
    ndarray of bool, shape (N,)
    """
    import sympy as sp

    closed = {u: law for u, law in scene.control.items() if u not in model.input_names
              and u in steady}
    out = np.zeros(len(Y), dtype=bool)
    if not closed:
        return out
    names = list(model.parameter_names) + list(model.names)
    columns = np.column_stack([P, Y])
    for u, law in sorted(closed.items()):
        f = sp.lambdify([sp.Symbol(n) for n in names], sp.sympify(law), modules="numpy")
        with np.errstate(all="ignore"):
            value = np.broadcast_to(np.asarray(f(*columns.T), dtype=complex), out.shape)
        want = np.asarray(steady[u], dtype=float)
        out |= ~(np.abs(value - want) <= LAW_TOL * np.maximum(1.0, np.abs(want)))
    return out
