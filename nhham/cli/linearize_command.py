"""``nhham linearize SCENE``: stability of the scene's ``[steady]`` motion.

Usage::

    nhham linearize SCENE [--json] [--exact | --numeric] [--sweep P=START:STOP:COUNT]
                          [--plot FILE]

The steady motion is linearised in independent coordinates on M_1
(:mod:`nhham.numerics.linearization`): state matrix, eigenvalues, verdict. Small
systems (n <= :data:`EXACT_MAX_N`) get the exact Jacobian
(:mod:`nhham.lagrangian.jacobian`) in the same chart, eigenvalues from it at
:data:`EXACT_DIGITS` digits; larger ones the complex-step Jacobian. With
``--sweep`` the parameter P takes COUNT values from START to STOP (the steady
state moves with it when its ``[steady]`` entries use P), and the crossings of
the imaginary axis are located by Brent's method. ``--plot`` draws the root
locus (needs the optional matplotlib extra; no global backend is set).

JSON (the ``result`` of the envelope, schema ``$defs/linearize``):
``coordinates``, ``matrix``, ``eigenvalues`` ([re, im] pairs), ``stable``
(bool or null), ``spectrally_stable``, ``method``, ``precision``, ``neutral``,
``dependent``, ``chart``, ``steady_state``; ``loop`` (``closed``: the scene's
``[control]`` laws replace its inputs, the keys above are the closed loop's),
``control``, ``open_loop`` (null, or the open loop's linearisation with
``inputs`` and ``input_matrix``); ``sweep`` (null without
``--sweep``) = {``parameter``, ``values``, ``eigenvalues``, ``crossings``
[{``value``, ``kind``}]}; ``plot`` (the file written, or null).
"""

from __future__ import annotations

import re
import warnings
import textwrap

from nhham.errors import InputError, NhhamWarning, OptionalDependencyError

__all__ = ["add_arguments", "cmd_linearize", "linearize_scene", "open_loop",
           "parse_sweep", "plot_root_locus", "root_locus_figure",
           "rounding_level", "EXACT_MAX_N", "EXACT_DIGITS", "LINEARIZE_HELP"]

#: (short help, description, example) for ``nhham linearize --help``.
LINEARIZE_HELP = (
    "stability of the [steady] motion: state matrix, eigenvalues, sweeps",
    "Linearise the constrained dynamics about the scene's [steady] motion (an equilibrium or "
    "a steady motion, checked to lie on M_1 and to be steady) in independent coordinates, "
    "neutral directions divided out: state matrix, eigenvalues and a stability verdict "
    "(exact for small systems, complex-step otherwise); with [control] laws the closed loop, "
    "and the open loop's (A, B) under it. --sweep moves a parameter (and the "
    "steady motion with it) and locates where an eigenvalue crosses the imaginary axis.",
    "nhham linearize examples/whipple_bicycle.toml --sweep v=0:10:101 --plot locus.png")

#: Largest number of coordinates for which ``auto`` uses the exact Jacobian.
EXACT_MAX_N = 4

#: Digits of the eigenvalues computed from an exact state matrix.
EXACT_DIGITS = 30

_SWEEP = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*=\s*([^:]+):([^:]+):([^:]+)\s*$")


def add_arguments(parser) -> None:
    """The command's own options (the common ones are added by ``main``)."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--exact", dest="method", action="store_const", const="exact",
                       help="exact (symbolic) Jacobian whatever the size")
    group.add_argument("--numeric", dest="method", action="store_const", const="complex-step",
                       help="complex-step Jacobian whatever the size")
    parser.set_defaults(method="auto")
    parser.add_argument("--sweep", metavar="P=START:STOP:COUNT", default=None,
                        help="eigenvalues along parameter P, with crossings located")
    parser.add_argument("--plot", metavar="FILE", default=None,
                        help="root-locus plot of the sweep (needs matplotlib)")


def parse_sweep(text: str):
    """``"v=0:10:101"`` -> ``("v", array of 101 values)``.

    Raises
    ------
    InputError
        Naming what is wrong with the option.
    """
    import numpy as np

    match = _SWEEP.match(text or "")
    if not match:
        raise InputError(f"--sweep: expected PARAMETER=START:STOP:COUNT (e.g. v=0:10:101), "
                         f"got {text!r}")
    name, a, b, c = match.groups()
    try:
        start, stop = float(a), float(b)
        count = int(c)
    except ValueError:
        raise InputError(f"--sweep: START and STOP must be numbers and COUNT an integer, "
                         f"got {text!r}") from None
    if not (np.isfinite(start) and np.isfinite(stop)) or count < 2 or stop <= start:
        raise InputError(f"--sweep: need finite START < STOP and COUNT >= 2, got {text!r}")
    if count > 100000:
        raise InputError(f"--sweep: COUNT {count} is too large (at most 100000)")
    return name, np.linspace(start, stop, count)


def linearize_scene(scene, method: str = "auto", sweep=None, model=None):
    """Linearise a scene's ``[steady]`` motion (and sweep a parameter).

    The scene's system is the one its runs integrate: with ``[control]`` laws, the
    closed loop (each input replaced by its law, :meth:`System.closed_loop`), whose
    verdict is the scene's; without, the system with its inputs at their ``[steady]``
    values. (The open loop's (A, B) of a scene with laws: :func:`open_loop`.)

    Parameters
    ----------
    scene : nhham.system.scene.Scene
        With a ``[steady]`` table.
    method : {"auto", "exact", "complex-step"}
    sweep : (str, array) or None
        Parameter name and values.
    model : NumericModel, optional
        Reuse a model of the scene's system (``scene.steady_system()``).

    Returns
    -------
    (Linearization, Sweep or None)

    Raises
    ------
    InputError
        No ``[steady]`` table; a ``[control]`` law that uses ``t`` (the closed loop has
        no steady motion) or that does not give the ``[steady]`` value of its input
        there (key ``control``).
    """
    from nhham.numerics.codegen import numeric_model
    from nhham.numerics.steady_sweep import sweep_steady

    _check_steady_table(scene)
    if method not in ("auto", "exact", "complex-step"):
        raise InputError(f"linearize: unknown method {method!r}")
    system = scene.steady_system()
    model = numeric_model(system) if model is None else model
    lin = _linearize(scene, system, model, method)
    result_sweep = None
    if sweep is not None:
        name, values = sweep
        result_sweep = sweep_steady(model, scene.steady.values, name, values,
                                    independent=lin.chart, family_of=scene.steady.family)
    return lin, result_sweep


def open_loop(scene, method: str = "auto", model=None, independent=None):
    """The open loop of a scene: its system with the inputs held at their ``[steady]``
    values, (A, B) of x' = A x + B u, whatever ``[control]`` says.

    Parameters
    ----------
    scene, method : as for :func:`linearize_scene`
    model : NumericModel, optional
        A model of ``scene.system``.
    independent : sequence of str, optional
        The chart (default: chosen at the state).

    Returns
    -------
    Linearization
    """
    from nhham.numerics.codegen import numeric_model

    _check_steady_table(scene)
    model = numeric_model(scene.system) if model is None else model
    return _linearize(scene, scene.system, model, method, independent)


def _check_steady_table(scene) -> None:
    if scene.steady is None:
        raise InputError(f"{scene.source}: linearize needs a [steady] table with a value (or an "
                         f"expression in the parameters) for every coordinate and velocity",
                         key="steady")


def _linearize(scene, system, model, method, independent=None):
    """The linearisation of ``system`` (``model``) about the scene's [steady] motion."""
    from nhham.numerics.linearization import linearize
    from nhham.numerics.steady_sweep import steady_state
    from nhham.system.force_checks import check_forces_at

    values = scene.steady.values(model.parameters)
    _check_laws(scene, system, model, values)
    check_forces_at(system, values, where="the [steady] motion")
    model, state = steady_state(model, values, independent)
    lin = linearize(model, state, family=scene.steady.family(model.parameters),
                    independent=independent)
    if method == "exact" or (method == "auto" and system.n <= EXACT_MAX_N):
        lin = _exact(scene, system, model, lin)
    return lin


def _check_laws(scene, system, model, values) -> None:
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
        if abs(value - want) > 1e-9 * max(1.0, abs(want)):
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

    params = {p.name: exact_number(v) for p, v in system.parameter_values.items()}
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
    for label in lin.neutral:
        if not label.startswith("d/d"):
            continue
        p = sp.Symbol(label[3:])   # a tangent of the steady family, divided out exactly
        t = sp.Matrix([sp.diff(scene.steady.expressions[s], p).xreplace(point) for s in names])
        j = max(range(len(names)), key=lambda i: abs(float(t[i])))
        T = sp.eye(len(names))
        T[:, j] = t
        B = T.LUsolve(A * T)
        rest = [i for i in range(len(names)) if i != j]
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
        exact_matrix=A, inputs=lin.inputs, B=lin.input_matrix)


def cmd_linearize(args, steps):
    """The command: load, linearise, sweep; a :class:`~nhham.cli.envelope.CommandOutput`."""
    from nhham.cli.envelope import CommandOutput, capture_warnings, scene_info
    from nhham.cli.loading import load_for
    from nhham.numerics.codegen import numeric_model
    from nhham.system.expressions import to_text

    with steps.step(f"load scene {args.scene}"):
        scene = load_for(args, check_initial=False)  # [steady], not [initial]
    args.loaded_scene = scene  # the envelope of a later failure names the scene
    sweep = parse_sweep(args.sweep) if args.sweep else None
    if args.plot and sweep is None:
        raise InputError("--plot draws the root locus of a sweep: give --sweep too")
    if args.plot:
        _matplotlib()  # fail before the work when the extra is missing
    with capture_warnings() as caught:
        with steps.step("numeric model (generated kernels)"):
            system = scene.steady_system()
            model = numeric_model(system)
        with steps.step(f"linearise ({args.method})"
                        + (" the closed loop ([control])" if scene.control else "")
                        + (f", sweep {args.sweep}" if sweep else "")):
            lin, swept = linearize_scene(scene, args.method, sweep, model=model)
        for u in () if swept is None else swept.unlocated:
            warnings.warn(f"--sweep: between {u.low:.10g} and {u.high:.10g}: {u.reason}; no "
                          f"crossing reported there", NhhamWarning)
        opened = None
        if scene.control:
            with steps.step(f"linearise ({args.method}) the open loop"):
                opened = open_loop(scene, args.method, independent=lin.chart)
    data = _json(lin)
    data["loop"] = "closed" if scene.control else "open"
    data["control"] = {u: to_text(law) for u, law in scene.control.items()}
    data["open_loop"] = None if opened is None else _json(opened)
    data["sweep"] = None if swept is None else swept.to_dict()
    data["plot"] = None
    if args.plot:
        with steps.step(f"plot {args.plot}"):
            data["plot"] = plot_root_locus(swept, args.plot, title=scene.name)
    return CommandOutput(result=data, text=lambda: _text(scene, lin, swept, args, opened),
                         scene=scene_info(scene), warnings=caught)


def _json(lin) -> dict:
    data = lin.to_dict()
    # -0.0 is 0.0 (x + 0.0 turns the one into the other; every other value is kept)
    data["matrix"] = [[x + 0.0 for x in row] for row in data["matrix"]]
    data["eigenvalues"] = [[re + 0.0, im + 0.0] for re, im in data["eigenvalues"]]
    return data


def _text(scene, lin, swept, args, opened=None) -> str:
    from nhham.cli.report import table
    from nhham.system.expressions import to_text

    closed = opened is not None
    lines = [f"{scene.name or args.scene}: linearisation about the [steady] motion"
             + (", the loop closed by its [control] laws" if closed else "")]
    rows = [
        ("method", lin.method),
        ("independent (chart)", ", ".join(lin.chart)),
        ("dependent", ", ".join(lin.dependent) or "none"),
        ("neutral (removed)", ", ".join(lin.neutral) or "none"),
        ("coordinates", ", ".join(lin.coordinates)),
        ("verdict", lin.verdict + (" (closed loop)" if closed else "")),
    ]
    if closed:
        rows += [("control", "; ".join(f"{u} = {to_text(law)}"
                                       for u, law in scene.control.items())),
                 ("open loop", opened.verdict + " (inputs held at their [steady] values)")]
    rows.append(("precision", lin.precision))
    lines.append(table(rows))
    lines += _matrices(lin, "state matrix" + (" of the closed loop" if closed else ""))
    if closed:
        lines.append("open loop (inputs held at their [steady] values):")
        lines.append(textwrap.indent("\n".join(_matrices(opened, "state matrix A")), "  "))
    if swept is not None:
        lines.append(f"sweep over {swept.parameter}: {len(swept.values)} values from "
                     f"{swept.values[0]:g} to {swept.values[-1]:g}")
        stable = [v for v, s in zip(swept.values, swept.stable) if s]
        lines.append(f"  stable at {len(stable)} of them"
                     + (f" (from {min(stable):g} to {max(stable):g})" if stable else ""))
        if swept.crossings:
            lines.append("crossings (Re of an eigenvalue changes sign):")
            lines.append(table([(f"{swept.parameter} = {c.value:.10f}", c.kind,
                                 "to Re > 0" if c.direction > 0 else "to Re < 0",
                                 f"lambda = {c.eigenvalue.real:.1e} {c.eigenvalue.imag:+.6f}i")
                                for c in swept.crossings]))
        else:
            lines.append("  no crossings")
    return "\n".join(lines)


def _matrices(lin, title) -> list:
    """The state matrix, B and the eigenvalues of ``lin`` as lines of text."""
    from nhham.cli.report import table

    lines = []
    floor = rounding_level(lin)
    shown_as_zero = False

    def num(x, digits, sign=""):
        nonlocal shown_as_zero
        if abs(x) <= floor:
            shown_as_zero |= x != 0
            return f"{0:{sign}.{digits}g}"
        return f"{x:{sign}.{digits}g}"

    if lin.matrix.size:
        lines.append(f"{title}:")
        lines.append(table([[num(x, 10) for x in row] for row in lin.matrix],
                           header=list(lin.coordinates)))
    if lin.inputs and lin.matrix.size:
        lines.append("input matrix B (x' = A x + B u, inputs at their [steady] values):")
        lines.append(table([[name] + [num(x, 10) for x in row]
                            for name, row in zip(lin.coordinates, lin.input_matrix)],
                           header=["", *lin.inputs]))
    lines.append("eigenvalues:")
    lines.append(table([(num(z.real, 12), num(z.imag, 12, "+") + "i")
                        for z in lin.eigenvalues] or [("none",)]))
    if shown_as_zero:
        lines.append(f"  (values of magnitude <= {floor:.1e} are shown as 0: rounding at this "
                     f"precision; --json has them as computed)")
    return lines


def rounding_level(lin) -> float:
    """The magnitude below which a number of ``lin`` is rounding, not a value.

    A complex-step Jacobian is exact up to rounding in each entry (about
    machine epsilon times the largest entry); eigenvalues from LAPACK are
    backward stable (errors about epsilon times the norm). 64 times that for
    float64; the exact method's matrix is exact and its eigenvalues are computed
    at :data:`EXACT_DIGITS` digits.
    """
    import numpy as np

    scale = max(1.0, float(np.abs(lin.matrix).max(initial=0.0)))
    eps = 10.0 ** -EXACT_DIGITS if lin.method == "exact" else float(np.finfo(float).eps)
    return 64 * eps * scale


def _matplotlib():
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError as exc:
        raise OptionalDependencyError(
            "plotting needs matplotlib, an optional extra: pip install 'nhham[plot]' "
            "(or pip install matplotlib)") from exc
    return Figure, FigureCanvasAgg


def plot_root_locus(swept, path, title: str = "") -> str:
    """Real and imaginary parts of the eigenvalues against the parameter; saved to ``path``.

    The crossings are drawn in the colours and words of
    :data:`nhham.study.plot_style.CROSSING_STYLE`, as in the stability maps of ``nhham
    sweep``; the legend sits right of the axes. Uses matplotlib's object API with the Agg
    canvas for this figure only (the user's pyplot backend is left alone).
    """
    fig = root_locus_figure(swept, title)
    fig.savefig(path, dpi=120)
    return str(path)


def root_locus_figure(swept, title: str = ""):
    """The Figure of :func:`plot_root_locus` (not saved)."""
    import numpy as np

    from nhham.study.plot_style import (CROSSING_STYLE, OUTSIDE_RIGHT, crossing_kind,
                                        legend_if_labelled)

    Figure, FigureCanvasAgg = _matplotlib()
    fig = Figure(figsize=(8.5, 5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    vals = swept.values
    re_pts = [(v, z.real) for v, ev in zip(vals, swept.eigenvalues) for z in ev]
    im_pts = [(v, abs(z.imag)) for v, ev in zip(vals, swept.eigenvalues) for z in ev if z.imag]
    if re_pts:
        x, y = zip(*re_pts)
        ax.plot(x, y, ".", markersize=3, color="k", label="Re(eigenvalue)")
    if im_pts:
        x, y = zip(*im_pts)
        ax.plot(x, y, ".", markersize=2, color="tab:gray", alpha=0.6, label="|Im(eigenvalue)|")
    for c in swept.crossings:
        style = CROSSING_STYLE[crossing_kind(c.kind)]
        ax.axvline(c.value, color=style["color"], linestyle=style["linestyle"], linewidth=1.0,
                   label=f"{style['label']} ({swept.parameter} = {c.value:.6g})")
    ax.axhline(0.0, color="k", linewidth=0.5)
    ax.set_xlabel(swept.parameter)
    ax.set_ylabel("eigenvalue")
    finite = [y for _, y in re_pts if np.isfinite(y)]
    if finite:
        lo = max(min(finite), -10.0 * max(1.0, max(abs(y) for _, y in im_pts) if im_pts else 1.0))
        ax.set_ylim(lo - 1.0, max(max(finite), max((y for _, y in im_pts), default=0.0)) + 1.0)
    ax.set_title(f"root locus: {title}" if title else "root locus")
    ax.grid(True, alpha=0.3)
    legend_if_labelled(ax, fontsize=7, **OUTSIDE_RIGHT)
    return fig
