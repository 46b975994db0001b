"""Figures of results (matplotlib, an optional extra: ``pip install 'nhham[plot]'``).

Every function takes an optional ``ax`` (or ``axes``) to draw into and returns
the :class:`matplotlib.figure.Figure`; without one it makes a new Figure
*without pyplot*, so no backend is chosen or changed here: in a notebook the
figure shows inline, and :func:`save_figure` writes it to a file. matplotlib
is imported only when a plot is asked for; without it an
:class:`~nhham.errors.OptionalDependencyError` says how to install it.

>>> fig = plot_trajectory(result)                     # doctest: +SKIP
>>> save_figure(fig, "trajectory.png")                # doctest: +SKIP
"""

from __future__ import annotations

import re

import numpy as np

from nhham.errors import OptionalDependencyError
from nhham.numerics.methods import lookup
from nhham.render.plot_style import OUTSIDE_RIGHT, legend_if_labelled, separate_tick_labels

__all__ = ["OptionalDependencyError", "plot_work_precision", "plot_trajectory", "save_figure",
           "plot_root_locus", "root_locus_figure", "require_matplotlib",
           "series_styles"]

_LINESTYLES = ("-", "--", "-.", ":")
_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*", "<", ">")


def series_styles(count: int) -> list:
    """``count`` distinguishable styles: dicts of colour, marker and line style.

    The first 10 use the 10 colours of matplotlib's "tab10" cycle with distinct
    markers; beyond 10 the markers and line styles change too, so no two series
    look alike however many there are.
    """
    from matplotlib import colormaps

    colours = getattr(colormaps["tab10"], "colors")  # a ListedColormap
    out = []
    for k in range(count):
        out.append({"color": colours[k % 10], "marker": _MARKERS[(k + k // 10) % len(_MARKERS)],
                    "linestyle": _LINESTYLES[(k // 10) % len(_LINESTYLES)]})
    return out


def save_figure(fig, path, dpi: int = 150) -> str:
    """Write a Figure to ``path`` (format from the suffix); returns the path."""
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    return str(path)


def _new_axes(nrows, figsize, sharex=True):
    Figure = require_matplotlib()[0]
    fig = Figure(figsize=figsize, layout="constrained")
    axes = fig.subplots(nrows, 1, sharex=sharex, squeeze=False)[:, 0]
    return fig, list(axes)


# -------------------------------------------------------------- trajectory
def plot_trajectory(result, axes=None, *, title: str | None = None):
    """Coordinates, velocities, constraint residual and energy over time, one panel each.

    Parameters
    ----------
    result : SimulationResult
    axes : sequence of 4 matplotlib Axes, optional
        Where to draw (coordinates, velocities, residual, energy); default a
        new Figure with four panels sharing the time axis.
    title : str, optional
        Figure title; default the method and the run's settings.

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    The scene gives no units, so axes are labelled with the quantities only
    (coordinates in the scene's units, velocities per unit time). Where the
    constraint residual is exactly zero (at t0, or after a projection) it is
    left out of the log-scale panel rather than clamped to a fake value.

    Examples
    --------
    >>> from nhham import models, simulate, plot_trajectory
    >>> run = simulate(models.rolling_disk(), (0.0, 1.0),
    ...                {"x": 0, "y": 0, "theta": 0, "phi": 0, "x_dot": 1, "y_dot": 0,
    ...                 "theta_dot": 1, "phi_dot": 1})
    >>> fig = plot_trajectory(run, title="rolling disk")
    >>> len(fig.axes)   # coordinates, velocities, residual, energy
    4
    """
    if axes is None:
        fig, axes = _new_axes(4, (9.0, 9.0))
    else:
        axes = list(axes)
        if len(axes) != 4:
            raise ValueError("plot_trajectory: axes must be 4 Axes (coordinates, velocities, "
                             "constraint residual, energy)")
        fig = axes[0].figure
    names = list(result.names)
    n = len(names) // 2
    t = np.asarray(result.t)
    Y = np.asarray(result.y)
    for ax, rows, label in ((axes[0], range(n), "coordinates q"),
                            (axes[1], range(n, 2 * n), "velocities dq/dt")):
        styles = series_styles(len(rows))
        every = max(1, len(t) // 12)
        for style, i in zip(styles, rows):
            ax.plot(t, Y[i], label=names[i], linewidth=1.2, markersize=4, markevery=every,
                    **style)
        ax.set_ylabel(label)
        # right of the panel, off the curves (inside, "best" still covered data)
        legend_if_labelled(ax, fontsize=8, ncol=1 + (len(rows) - 1) // 12, **OUTSIDE_RIGHT)
        ax.grid(True, alpha=0.3)
    res = np.asarray(result.diagnostics.constraint_residual, dtype=float)
    ax = axes[2]
    positive = res > 0
    if positive.any():
        ax.semilogy(t, np.where(positive, res, np.nan), color="black", linewidth=1)
        if not positive.all():
            # right of the panel, where the other panels have their legends: off the data
            ax.text(1.02, 1.0, f"exactly 0 at\n{int((~positive).sum())} of {len(res)}\n"
                    "points (not drawn)", transform=ax.transAxes, fontsize=8, va="top")
    else:
        ax.text(0.5, 0.5, "constraint residual exactly 0 at every stored point",
                transform=ax.transAxes, ha="center", va="center", fontsize=9)
    ax.set_ylabel("max |constraint\nresidual|")
    ax.grid(True, which="both", alpha=0.3)
    ax = axes[3]
    energy = np.asarray(result.energy, dtype=float)
    ax.plot(t, energy - energy[0], label="E(t) - E(0)", color="tab:blue", linewidth=1.2)
    if result.work is not None:
        forced = result.model is not None and result.model.forced
        ax.plot(t, np.asarray(result.work, dtype=float), "--", color="tab:red", linewidth=1.2,
                label="work of the applied, dissipative and constraint forces" if forced
                else "work of the constraint forces")
    ax.set_ylabel("energy change")
    ax.set_xlabel("time t")
    legend_if_labelled(ax, fontsize=8, **OUTSIDE_RIGHT)
    ax.grid(True, alpha=0.3)
    if title is None:
        title = f"{result.method}: {_settings_text(result)}"
    fig.suptitle(title)
    return fig


def _settings_text(result) -> str:
    s = dict(result.settings)
    method = lookup(result.method)
    if method.fixed_step:
        return f"step {s.get('step')}"
    if method.reference:
        return f"mpmath {s.get('digits')} digits"
    text = f"rtol {s.get('rtol'):g}" if s.get("rtol") is not None else ""
    return text + (", projection" if s.get("projection") else "")


# ---------------------------------------------------------- work-precision
def _setting_value(setting: str) -> float:
    """The number in ``"rtol=1e-08"`` or ``"h=0.01"`` (nan if none)."""
    m = re.search(r"=\s*([-+0-9.eE]+)", setting)
    try:
        return float(m.group(1)) if m else float("nan")
    except ValueError:
        return float("nan")


def plot_work_precision(result, ax=None, *, title: str | None = None):
    """Error at t_end against wall time, log-log: one colour per method.

    Parameters
    ----------
    result : WorkPrecisionResult
    ax : matplotlib Axes, optional
        Where to draw; default a new Figure.
    title : str, optional
        Default ``"work-precision: <system name>"``.

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    A method and its ``+projection`` variant share a colour and a marker; the
    variant is dashed. Each line joins the runs in the order of their
    setting (tolerance or step, coarse to fine), so a line never zig-zags
    because two runs happened to take the same time. Runs that failed or
    whose error is not positive and finite are not drawn.

    Examples
    --------
    >>> from nhham import loads_scene, bench, plot_work_precision
    >>> scene = loads_scene('''
    ... coordinates = ["x"]
    ... lagrangian = "x_dot**2/2 - x**2/2"
    ... constraints = []
    ... [initial]
    ... x = 1.0
    ... x_dot = 0.0
    ... ''')
    >>> fig = plot_work_precision(bench(scene, t_end=1.0, quick=True).payload["result"])
    >>> fig.axes[0].get_xscale(), fig.axes[0].get_yscale()
    ('log', 'log')
    """
    if ax is None:
        Figure = require_matplotlib()[0]
        fig = Figure(figsize=(7.5, 5.5), layout="constrained")
        ax = fig.subplots()
    fig = ax.figure
    labels = list(result.methods())
    bases = list(dict.fromkeys(m.split("+")[0] for m in labels))
    styles = dict(zip(bases, series_styles(len(bases))))
    drawn = 0
    times = []
    for label in labels:
        rows = [r for r in result.rows if r.method == label and r.status == 0
                and np.isfinite(r.error) and r.error > 0]
        if not rows:
            continue
        rows.sort(key=lambda r: -_setting_value(r.setting))
        style = dict(styles[label.split("+")[0]])
        if "+" in label:
            style.update(linestyle="--", markerfacecolor="none")
        ax.loglog([r.wall_time_s for r in rows], [r.error for r in rows], label=label,
                  linewidth=1.3, markersize=5, **style)
        times += [r.wall_time_s for r in rows if r.wall_time_s > 0]
        drawn += 1
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel("relative error at t_end")
    ax.set_title(title or f"work-precision: {result.name or 'system'}")
    ax.grid(True, which="both", alpha=0.3)
    if times:
        _log_ticks(ax.xaxis, min(times), max(times))
    projected = any("+" in label for label in labels)
    legend_if_labelled(ax, fontsize=7, title="dashed: + projection" if projected else None,
                       title_fontsize=7, **OUTSIDE_RIGHT)
    if times:
        separate_tick_labels(ax.xaxis)   # at the figure's size, legend placed
    return fig


def _log_ticks(axis, lo: float, hi: float) -> None:
    """Tick labels of a log axis: decades when the data span two or more, else 1, 2 and
    5 times a power of 10 in short numbers (``%.3g``); minor ticks unlabelled.
    (matplotlib's default labels every minor tick of a short span, ``3x10^-4``,
    ``4x10^-4``, ..., and these collide;
    :func:`~nhham.render.plot_style.separate_tick_labels` thins what is still too dense
    for the axes' width.)"""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    if np.log10(hi / lo) >= 2.0:
        axis.set_major_locator(LogLocator(base=10.0, numticks=12))
    else:
        axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.3g}"))
    axis.set_minor_locator(LogLocator(base=10.0, subs=tuple(range(2, 10)), numticks=12))
    axis.set_minor_formatter(NullFormatter())


def require_matplotlib():
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
    :data:`nhham.render.plot_style.CROSSING_STYLE`, as in the stability maps of ``nhham
    sweep``; the legend sits right of the axes. Uses matplotlib's object API with the Agg
    canvas for this figure only (the user's pyplot backend is left alone).

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np
    >>> from nhham import loads_scene, linearize, plot_root_locus
    >>> scene = loads_scene('''
    ... coordinates = ["x"]
    ... parameters = { c = 0.5 }
    ... lagrangian = "x_dot**2/2 - x**2/2"
    ... dissipation = "c*x_dot**2/2"
    ... [steady]
    ... x = 0.0
    ... x_dot = 0.0
    ... ''')
    >>> swept = linearize(scene, sweep=("c", np.linspace(-1, 1, 21))).payload["sweep"]
    >>> [(c.kind, round(c.value, 9)) for c in swept.crossings]   # damping through 0
    [('complex', 0.0)]
    >>> path = plot_root_locus(swept, os.path.join(tempfile.mkdtemp(), "locus.png"))
    >>> os.path.getsize(path) > 0
    True
    """
    fig = root_locus_figure(swept, title)
    fig.savefig(path, dpi=120)
    return str(path)


def root_locus_figure(swept, title: str = ""):
    """The Figure of :func:`plot_root_locus` (not saved)."""
    import numpy as np

    from nhham.render.plot_style import CROSSING_STYLE, crossing_kind

    Figure, FigureCanvasAgg = require_matplotlib()
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
