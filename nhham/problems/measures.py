"""How nhham computes a published quantity: one function per kind, in :data:`MEASURES`.

Each measure takes the problem's :class:`~nhham.problems.runner.Context` (its scene and
compiled model, loaded once, at other parameter values on request), the quantity's
``args`` (from ``catalog.toml``) and returns a :class:`Measured`: the value
(a number, or a list of [re, im] pairs for a spectrum), the method that produced it and
the seconds it took. Closed forms are evaluated by :func:`closed_form` at the scene's
parameter values and initial data (``NAME_0`` for the initial value of a state ``NAME``).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np

from nhham.numerics.methods import DEFAULT_METHOD

__all__ = ["Measured", "MEASURES", "closed_form", "completed_state", "defined",
           "spectrum_error"]


@dataclass(frozen=True)
class Measured:
    """nhham's value of a quantity.

    Attributes
    ----------
    value : float or list
        A number, or for a spectrum a list of [re, im] pairs.
    method : str
        What computed it (the command's route, the integrator and its tolerance).
    time_s : float
        Wall seconds of the computation (the scene loaded and compiled beforehand).
    extra : mapping
        What else the measure found (the IFToMM run's CPU time and file).
    """

    value: Any
    method: str
    time_s: float
    extra: Mapping | None = None


def _symbols(scene):
    """Names a closed form may use: parameters, states, ``NAME_0`` and t."""
    import sympy as sp

    names = {p.name: p for p in scene.system.parameters}
    names.update({s.name: s for s in scene.system.state})
    names.update({f"{s.name}_0": sp.Symbol(f"{s.name}_0") for s in scene.system.state})
    names["t"] = sp.Symbol("t")
    return names


def closed_form(scene, text, *, t=None, initial=None, values=None) -> float:
    """The value of a closed form ``text`` (parsed against the scene's names, never
    evaluated as Python) at the scene's parameter values, its initial data as ``NAME_0``
    and time ``t``.

    Examples
    --------
    >>> import nhham
    >>> scene = nhham.loads_scene('coordinates = ["x"]\\nparameters = { g = 9.81, r = 0.26 }\\n'
    ...                           'lagrangian = "x_dot**2/2"')
    >>> round(closed_form(scene, "sqrt(g/(3*r))"), 12)
    3.546395786841
    """
    import sympy as sp

    from nhham.system.expressions import parse_expression

    names = _symbols(scene)
    expr = parse_expression(text, names, where="published")
    sub = dict(scene.system.parameter_values)
    sub.update({names[k]: v for k, v in (values or {}).items()})
    sub.update({names[f"{k}_0"]: v for k, v in (initial or {}).items()})
    if t is not None:
        sub[names["t"]] = t
    value = expr.xreplace({k: sp.Float(v, 30) for k, v in sub.items()}).evalf(30)
    if value.free_symbols:
        raise ValueError(f"closed form {text!r}: no value for {sorted(map(str, value.free_symbols))}")
    return float(value)


def defined(context) -> dict:
    """The problem's ``define`` table as expressions in the scene's names (name ->
    sympy expression; each entry may use the entries before it)."""
    import sympy as sp

    from nhham.system.expressions import parse_expression

    names = _symbols(context.scene())
    out: dict = {}
    for name, text in context.problem.define.items():
        expr = parse_expression(text, {**names, **{k: sp.Symbol(k) for k in out}},
                                where=f"define.{name}")
        out[name] = expr.xreplace({sp.Symbol(k): v for k, v in out.items()})
    return out


def _parsed(context, texts, names, where):
    """``texts`` parsed against the scene's and the ``define`` names (or ``names``), the
    definitions substituted and the parameters at the scene's values."""
    import sympy as sp

    from nhham.system.expressions import parse_expression

    known = defined(context)
    table = {**_symbols(context.scene()), **{k: sp.Symbol(k) for k in known},
             **{k: sp.Symbol(k) for k in names}}
    sub = {sp.Symbol(k): v for k, v in known.items() if k not in names}
    values = {p: sp.Float(v) for p, v in context.scene().system.parameter_values.items()}
    return [parse_expression(t, table, where=f"{where}[{i}]").xreplace(sub).xreplace(values)
            for i, t in enumerate(texts)]


def evaluator(context, texts):
    """The expressions ``texts`` as a function of a state (name -> number or array)."""
    import sympy as sp

    state = list(context.scene().system.state)
    f = sp.lambdify(state, _parsed(context, texts, (), "expression"), "numpy")
    return lambda y: np.array(np.broadcast_arrays(*f(*[y[s.name] for s in state])),
                              dtype=float)


def spectrum_error(value, published) -> float:
    """The largest distance between two spectra, matched greedily (nearest first)."""
    got = [complex(*z) for z in value]
    want = [complex(*z) for z in published]
    worst = 0.0
    for w in want:
        j = int(np.argmin([abs(w - z) for z in got]))
        worst = max(worst, abs(w - got.pop(j)))
    return worst


def _timed(fn):
    start = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - start


def eigenvalues(context, args) -> Measured:
    """The eigenvalues of ``nhham linearize`` at the scene's [steady] motion with the
    ``parameter`` at ``value`` (a sweep of one value: the scene loaded once), the other
    parameters at the scene's values or ``set``."""
    from nhham.journeys.stability import linearize

    sweep = (args["parameter"], np.array([float(args["value"])]))
    values = args.get("set")
    answer, seconds = _timed(lambda: linearize(context.scene(values), sweep=sweep,
                                               model=context.model(values)))
    data = answer.to_dict()
    return Measured([[float(re), float(im)] for re, im in data["sweep"]["eigenvalues"][0]],
                    f"linearize --sweep {args['parameter']}={args['value']:g} "
                    f"({data['method']})", seconds)


def crossing(context, args) -> Measured:
    """Where ``nhham linearize --sweep`` finds the spectrum crossing the imaginary axis
    (the first crossing of ``kind``, "real" or "complex", in the range; the other
    parameters at the scene's values or ``set``)."""
    from nhham.journeys.stability import linearize

    lo, hi, count = args["range"]
    sweep = (args["parameter"], np.linspace(lo, hi, int(count)))
    values = args.get("set")
    answer, seconds = _timed(lambda: linearize(context.scene(values), sweep=sweep,
                                               model=context.model(values)))
    swept = answer.to_dict()["sweep"]
    found = [c for c in swept["crossings"] if c["kind"] == args["kind"]]
    if not found:
        raise ValueError(f"no {args['kind']} crossing of {args['parameter']} in {lo}..{hi}")
    value = float(found[0]["value"])
    return Measured(value, f"linearize --sweep {args['parameter']}", seconds,
                    extra={"floor": _crossing_floor(swept, found[0])})


def _crossing_floor(swept, crossing) -> float:
    """How well double precision places a crossing: the rounding of the spectrum (16 eps
    of its largest |eigenvalue| there) over the slope of the crossing eigenvalue's real
    part (the eigenvalue nearest the crossing's at the grid values on either side; 0,
    no allowance, where that slope is 0)."""
    values = np.asarray(swept["values"], dtype=float)
    i = int(np.clip(np.searchsorted(values, crossing["value"]), 1, len(values) - 1))
    at = complex(*crossing["eigenvalue"])
    spectra = [np.array([complex(*z) for z in swept["eigenvalues"][j]]) for j in (i - 1, i)]
    size = max(float(np.abs(s).max()) for s in spectra)
    re = [float(s[np.argmin(np.abs(s - at))].real) for s in spectra]
    slope = abs(re[1] - re[0]) / (values[i] - values[i - 1])
    return 16 * float(np.finfo(float).eps) * size / slope if slope else 0.0


def _run(context, t_end, t_eval=None, start=None):
    """The scene's [initial] motion (or the motion from ``start``) to t_end (DOP853,
    rtol 1e-12, atol 1e-14)."""
    from nhham.numerics.integrate import simulate

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return simulate(context.model(), (0.0, t_end), start or context.initial(), warn=False,
                        t_eval=t_eval, method=DEFAULT_METHOD, rtol=1e-12, atol=1e-14)


def completed_state(scene, given, values=None) -> dict:
    """The state whose independent entries are ``given`` (name -> number), the others
    solved from the constraints (:func:`nhham.system.initial_solve.complete_initial`), at
    the parameter ``values`` (default: the scene's)."""
    import sympy as sp

    from nhham.system.initial_solve import InitialData, complete_initial

    data = InitialData(given={k: sp.Float(v) for k, v in given.items()})
    return complete_initial(scene.system, data, values)[0]


def _state_at(result, i) -> dict:
    return {name: float(result[name][i]) for name in result.names}


def trajectory(context, args) -> Measured:
    """An expression (in the scene's names and the problem's ``define``) of the state at
    time ``t`` of the scene's [initial] motion, or with ``initial`` (name -> number or
    closed form in the scene's parameters and the numbers given) of that state completed
    from the constraints; ``extra["initial"]`` is the state the closed form is read at."""
    start = None
    if "initial" in args:
        scene = context.scene()
        given = {k: v for k, v in args["initial"].items() if not isinstance(v, str)}
        given.update({k: closed_form(scene, v, values=given)
                      for k, v in args["initial"].items() if isinstance(v, str)})
        start = completed_state(scene, given)
    result, seconds = _timed(lambda: _run(context, args["t"], start=start))
    value = float(evaluator(context, [args["expression"]])(_state_at(result, -1))[0])
    return Measured(value, f"simulate {DEFAULT_METHOD} rtol 1e-12", seconds,
                    extra={"initial": start} if start else None)


def turning_rate(context, args) -> Measured:
    """The mean rate at which the vector (``vector`` of two state names) turns over the
    run to ``t``: its unwrapped angle's change over the time."""
    grid = np.linspace(0.0, args["t"], 2001)
    result, seconds = _timed(lambda: _run(context, args["t"], t_eval=grid))
    u, v = (np.asarray(result[name]) for name in args["vector"])
    angle = np.unwrap(np.arctan2(v, u))
    return Measured(float((angle[-1] - angle[0]) / (grid[-1] - grid[0])),
                    f"simulate {DEFAULT_METHOD} rtol 1e-12", seconds)


def mean_velocity(context, args) -> Measured:
    """The mean velocity of the point (``vector``: two coordinates) over ``periods``
    periods 2 pi/rate: its size, or with ``component`` that component."""
    period = 2 * np.pi / closed_form(context.scene(), args["rate"])
    t_end = args["periods"] * period
    result, seconds = _timed(lambda: _run(context, t_end))
    ends = np.array([[result[name][0], result[name][-1]] for name in args["vector"]])
    mean = (ends[:, 1] - ends[:, 0]) / t_end
    value = float(np.hypot(*mean)) if "component" not in args else float(mean[args["component"]])
    return Measured(value, f"simulate {DEFAULT_METHOD} rtol 1e-12", seconds)


def classify(context, args) -> Measured:
    """A field of ``nhham classify --json``'s result (with ``count``: its length)."""
    from nhham.journeys.verdict import classify as run

    if "classify" not in context.cache:   # every field from one run
        context.cache["classify"] = _timed(lambda: run(context.scene()).to_dict())
    data, seconds = context.cache["classify"]
    value = data[args["field"]]
    return Measured(len(value) if args.get("count") else value, "classify", seconds)


def iftomm(context, args) -> Measured:
    """The IFToMM maneuver's energy error 100 (max E - min E)/E_0 in % (:mod:`.iftomm`)."""
    run = context.maneuver(args["maneuver"])
    return Measured(run.energy_error_percent, f"simulate {run.method}",
                    run.integration_s, extra={"maneuver": run})


def spin_reversal(context, args) -> Measured:
    """The first time the state ``spin`` changes sign, from ``initial`` (given entries;
    the rest from the constraints) at the parameters ``set``: by the two ``methods``
    (the second the second route; both rtol 1e-12, atol 1e-14), on a grid of 1e-3 s
    refined by linear interpolation. ``extra["second_route"]``: the second route's time."""
    from nhham.numerics.integrate import simulate

    values = args.get("set")
    model = context.model(values)
    y0 = completed_state(context.scene(values), args["initial"], values)
    grid = np.linspace(0.0, args["t_end"], int(round(args["t_end"] * 1000)) + 1)
    times = []
    start = time.perf_counter()
    first, second = args["methods"]
    for method in (first, second):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = simulate(model, (0.0, args["t_end"]), y0, method=method,
                                    rtol=1e-12, atol=1e-14, t_eval=grid, warn=False)
        w = np.asarray(result[args["spin"]])
        flips = np.flatnonzero(np.sign(w[1:]) != np.sign(w[:-1]))
        if not flips.size:
            raise ValueError(f"{args['spin']} keeps its sign to t = {args['t_end']}")
        i = int(flips[0])
        times.append(float(grid[i] - w[i] * (grid[i + 1] - grid[i]) / (w[i + 1] - w[i])))
        if len(times) == 1:
            seconds = time.perf_counter() - start
    return Measured(times[0], f"simulate {first} rtol 1e-12 (second route {second} rtol "
                              f"1e-12)", seconds, extra={"second_route": times[1]})


def acceleration(context, args) -> Measured:
    """``sign`` times the acceleration of ``coordinate`` at the state whose independent
    entries are ``given`` (the rest from the constraints): the field's own evaluation
    (the compiled or generated right-hand side), computed once for every quantity."""
    if "accelerations" not in context.cache:
        start = time.perf_counter()
        scene, model = context.scene(), context.model()
        state = completed_state(scene, args["given"])
        dy = model.evaluate(model.state(state))[0]
        names = [c.name for c in scene.system.coordinates]
        context.cache["accelerations"] = (dict(zip(names, dy[model.n:].tolist())),
                                          time.perf_counter() - start)
    accelerations, seconds = context.cache["accelerations"]
    return Measured(args.get("sign", 1.0) * accelerations[args["coordinate"]],
                    "the constrained field at the state", seconds)


def integral_drift(context, args) -> Measured:
    """The largest change of ``expression`` along the scene's [initial] motion to ``t``
    (2001 samples), relative to its initial value: max |F(t) - F(0)| / |F(0)|."""
    grid = np.linspace(0.0, args["t"], 2001)
    key = ("samples", args["t"])   # one run for every integral of the problem
    if key not in context.cache:
        context.cache[key] = _timed(lambda: _run(context, args["t"], t_eval=grid))
    result, seconds = context.cache[key]
    f = evaluator(context, [args["expression"]])(
        {name: np.asarray(result[name]) for name in result.names})[0]
    return Measured(float(np.max(np.abs(f - f[0])) / abs(f[0])),
                    f"simulate {DEFAULT_METHOD} rtol 1e-12", seconds)


def invariant_measure(context, args) -> Measured:
    """How far the flow moves the measure rho d^N x: the ratio
    nu(x(t)) |det du(t)/du(0)| / nu(x(0)), 1 for an invariant measure.

    ``ambient`` names the coordinates x (in the problem's ``define``) in which the source
    writes the density ``density`` (rho, in those names); ``integrals`` are functions of x
    the motion keeps (|gamma|^2, a constraint), ``chart`` coordinates u on their level set,
    so that the measure there has the density nu = rho / |det d(u, F)/dx|. The Jacobian
    du(t)/du(0) is found by central differences (``step``, default 1e-5: an error of
    about 1e-8, as step^2) of runs from the [initial] state with each entry of ``vary``
    moved (the ``given`` entries kept, the rest completed from the constraints), to ``t``.
    ``extra["note"]``: the same ratio for the density 1 (the check's contrast)."""
    import sympy as sp

    ambient = [sp.Symbol(name) for name in args["ambient"]]
    names = args["ambient"]
    chart = _parsed(context, args["chart"], names, "chart")
    keep = _parsed(context, args["integrals"], names, "integrals")
    rho = _parsed(context, [args["density"]], names, "density")[0]
    det = sp.Matrix(chart + keep).jacobian(ambient).det()
    density = sp.lambdify(ambient, [rho / sp.Abs(det), 1 / sp.Abs(det)], "numpy")
    to_x = evaluator(context, args["ambient"])
    to_u = sp.lambdify(ambient, chart, "numpy")
    scene, base = context.scene(), context.initial()
    given = {k: v for k, v in base.items() if k in args["given"]}
    h = args.get("step", 1e-5)
    start = time.perf_counter()

    def ends(name, sign):
        y0 = completed_state(scene, {**given, name: given[name] + sign * h})
        y1 = _state_at(_run(context, args["t"], start=y0), -1)
        return [np.array(to_u(*to_x(y)), dtype=float) for y in (y0, y1)]

    columns = [[(p - m) / (2 * h) for p, m in zip(ends(name, 1), ends(name, -1))]
               for name in args["vary"]]
    jac0, jac1 = (np.column_stack([c[i] for c in columns]) for i in (0, 1))
    final = _state_at(_run(context, args["t"], start=base), -1)
    (rho0, lebesgue0), (rho1, lebesgue1) = (density(*to_x(y)) for y in (base, final))
    growth = abs(np.linalg.det(jac1) / np.linalg.det(jac0))
    return Measured(float(rho1 * growth / rho0), f"simulate {DEFAULT_METHOD} rtol 1e-12, "
                    "central differences", time.perf_counter() - start,
                    extra={"note": "with the density 1 instead: "
                                   f"{lebesgue1 * growth / lebesgue0:.6g}"})


#: The measures by name: ``measure = "NAME"`` in ``catalog.toml``.
MEASURES: Mapping[str, Callable] = {
    "eigenvalues": eigenvalues,
    "crossing": crossing,
    "trajectory": trajectory,
    "turning_rate": turning_rate,
    "mean_velocity": mean_velocity,
    "classify": classify,
    "iftomm": iftomm,
    "spin_reversal": spin_reversal,
    "acceleration": acceleration,
    "integral_drift": integral_drift,
    "invariant_measure": invariant_measure,
}
