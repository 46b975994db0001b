"""Pictures of a study's Dataset (matplotlib, the plot extra).

- :func:`plot_stability_map`: linearize over two parameters: each cell tinted by its
  verdict (stable, unstable, undecided), the first ``--over`` (or ``along``) across, with
  the located boundaries drawn as curves (a complex pair crossing the imaginary axis,
  e.g. a bicycle's weave speed; a real eigenvalue crossing 0, its capsize speed), and
  those located along the second axis (``boundary_across``) as marked points on the
  same colours (the edge of the stable region where it runs along the first axis); over
  one parameter, the spectral abscissa with the stable stretches tinted and the
  boundaries marked; over samples, the points coloured by their verdict.
- :func:`plot_ensemble`: simulate: the spread of the end states (the first two swept or
  perturbed names, or the first two coordinates) and the runs' energy errors (a
  histogram when they spread, else the numbers written in the panel).
- :func:`plot_cases`: classify: each point's case, the first ``--over`` across, a legend
  of the cases present (the generic verdict in grey).

Colours and words are those of :mod:`nhham.render.plot_style`, shared with the root locus
of ``nhham linearize --sweep --plot``; every legend sits right of the axes, off the data,
and is drawn only when there is something to label.

Each returns a :class:`matplotlib.figure.Figure` made without pyplot (no backend is
chosen here); :func:`plot_study` picks the picture of a Dataset and saves it.
"""

from __future__ import annotations

import json

import numpy as np

from nhham.errors import OptionalDependencyError
from nhham.render.plot_style import (CROSSING_STYLE, OUTSIDE_RIGHT, VERDICT_STYLE, case_colour,
                                    crossing_kind, legend_if_labelled, separate_tick_labels)

__all__ = ["plot_study", "plot_stability_map", "plot_ensemble", "plot_cases", "pyplot"]


def pyplot():
    """matplotlib's Figure class, or the error naming the extra."""
    try:
        from matplotlib.figure import Figure
    except ImportError:
        raise OptionalDependencyError(
            "pictures of a study need matplotlib, an optional extra: pip install "
            "'nhham[plot]'") from None
    return Figure


def plot_study(ds, path, dpi: int = 150) -> str:
    """Draw the picture of a study's Dataset (by its kind) and save it to ``path``.

    Parameters
    ----------
    ds : xarray.Dataset
        A study's results (:attr:`SweepResult.dataset <nhham.study.sweep.SweepResult>`).
    path : str or os.PathLike
        The image file; its suffix chooses the format (``.png``, ``.pdf``, ``.svg``).
    dpi : int, optional
        Resolution of a raster image.

    Returns
    -------
    str
        ``path``.

    Examples
    --------
    >>> import os, tempfile
    >>> from nhham import plot_study
    >>> from nhham.study.sweep import sweep
    >>> ds = sweep("examples/parametric_null_constraint.toml", "classify", ["b=0.5,1.0"],
    ...            workers=1).dataset
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = plot_study(ds, os.path.join(folder, "cases.png"), dpi=50)
    ...     with open(path, "rb") as image:
    ...         image.read(4)
    b'\\x89PNG'
    """
    from nhham.study.kinds import kind_of

    fig = globals()[kind_of(ds.attrs.get("what")).plot](ds)
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    return str(path)


def _design_dims(ds) -> tuple:
    return tuple(ds["done"].dims)


def _title(ds) -> str:
    source = ds.attrs.get("scene_source", "")
    return f"{source.rsplit('/', 1)[-1]}: {ds.attrs.get('what', '')}"


def plot_stability_map(ds, ax=None):
    """The stability of a linearize study (see the module docstring).

    Parameters
    ----------
    ds : xarray.Dataset
        A linearize study's results.
    ax : matplotlib.axes.Axes, optional
        Where to draw (default: the axes of a new Figure).

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    The sleigh with drag (see the scene): with J = I + m a^2 = 0.5, the drag's eigenvalue
    is -3 k U^2 / m = -0.9 U^2 and the yaw's -(m a U + c) / J = U - 0.8, so the spectral
    abscissa is the larger, and the boundary is drawn at U* = 0.8.

    >>> from nhham import plot_stability_map
    >>> from nhham.study.sweep import sweep
    >>> ds = sweep("tests/study/scenes/sleigh_drag.toml", "linearize", ["U=0.3:1.3:6"],
    ...            workers=1).dataset
    >>> ax, = plot_stability_map(ds).axes
    >>> ax.get_xlabel(), ax.get_ylabel()
    ('U', 'max Re(eigenvalue)')
    >>> ax.lines[0].get_xydata().round(3).tolist()
    [[0.3, -0.081], [0.5, -0.225], [0.7, -0.1], [0.9, 0.1], [1.1, 0.3], [1.3, 0.5]]
    >>> [round(float(u), 6) for u in ax.lines[2].get_xdata()]
    [0.8, 0.8]
    """
    fig, ax = _axes(ax)
    dims = _design_dims(ds)
    done = np.asarray(ds["done"].values, dtype=bool)
    verdict = np.where(done, np.asarray(ds["verdict"].values, dtype=float), np.nan)
    if dims == ("sample",):
        names = _sample_names(ds)
        x = ds.coords[names[0]].values
        y = ds.coords[names[1]].values if len(names) > 1 else np.zeros_like(x)
        for value in (1, 0, -1):
            pick = verdict == value
            if pick.any():
                style = VERDICT_STYLE[value]
                ax.scatter(x[pick], y[pick], s=6, color=style["color"], label=style["label"])
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1] if len(names) > 1 else "")
        legend_if_labelled(ax, fontsize=8, **OUTSIDE_RIGHT)
    elif len(dims) == 1:
        x = ds.coords[dims[0]].values
        ax.plot(x, ds["spectral_abscissa"].values, color="k", lw=1.2,
                label="max Re(eigenvalue)")
        ax.axhline(0.0, color="0.5", lw=0.8)
        _verdict_bands(ax, x, verdict)
        _mark_boundaries_1d(ds, ax, dims[0])
        ax.set_xlabel(dims[0])
        ax.set_ylabel("max Re(eigenvalue)")
        legend_if_labelled(ax, fontsize=8, **OUTSIDE_RIGHT)
    else:
        along = json.loads(ds.attrs.get("options", "{}")).get("along") or dims[0]
        other = next(d for d in dims if d != along)
        shown = ds["verdict"].where(ds["done"]).transpose(other, along, ...)
        if shown.ndim > 2:   # more swept parameters: the first value of the others
            shown = shown.isel({d: 0 for d in shown.dims[2:]})
        X, Y = ds.coords[along].values, ds.coords[other].values
        handles = _verdict_mesh(ax, X, Y, np.asarray(shown.values, dtype=float))
        handles += _boundaries_2d(ds, ax, other)
        handles += _boundaries_across_2d(ds, ax, along, other)
        ax.set_xlabel(along)
        ax.set_ylabel(other)
        ax.set_xlim(X.min(), X.max())
        ax.set_ylim(Y.min(), Y.max())
        legend_if_labelled(ax, handles=handles, fontsize=8, **OUTSIDE_RIGHT)
    ax.set_title(_title(ds), fontsize=9)
    return fig


def _verdict_bands(ax, x, verdict) -> None:
    """Stretches of one verdict tinted as the map's cells (the unstable ones too, so that
    every colour is in the legend): each point's stretch reaches halfway to its
    neighbours."""
    order = np.argsort(x)
    x, verdict = np.asarray(x, dtype=float)[order], verdict[order]
    mid = (x[1:] + x[:-1]) / 2
    edges = np.concatenate([[x[0]], mid, [x[-1]]])
    labelled = set()
    start = 0
    for i in range(1, len(x) + 1):
        if i < len(x) and verdict[i] == verdict[start]:
            continue
        value = verdict[start]
        if value in (1, 0, -1):
            style = VERDICT_STYLE[int(value)]
            ax.axvspan(edges[start], edges[i], color=style["fill"], lw=0, zorder=0,
                       label=style["label"] if value not in labelled else "_nolegend_")
            labelled.add(value)
        start = i


def _verdict_mesh(ax, X, Y, verdict) -> list:
    """Cells tinted by verdict (not computed: left blank); the legend's proxy patches of
    the verdicts present, in the cells' colours."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    present = [v for v in (1, 0, -1) if (verdict == v).any()]
    if not present:
        return []
    index = np.full(verdict.shape, np.nan)
    for i, v in enumerate(present):
        index[verdict == v] = i
    cmap = ListedColormap([VERDICT_STYLE[v]["fill"] for v in present])
    ax.pcolormesh(X, Y, np.ma.masked_invalid(index), cmap=cmap, vmin=-0.5,
                  vmax=len(present) - 0.5, shading="nearest", rasterized=True)
    handles = [Patch(facecolor=VERDICT_STYLE[v]["fill"], edgecolor="0.5",
                     label=VERDICT_STYLE[v]["label"]) for v in present]
    if np.isnan(verdict).any():
        handles.append(Patch(facecolor="white", edgecolor="0.5", hatch="///",
                             label="not computed"))
        ax.set_facecolor("white")
        ax.patch.set_hatch("///")
        ax.patch.set_edgecolor("0.85")
    return handles


def _mark_boundaries_1d(ds, ax, name) -> None:
    if "boundary" not in ds:
        return
    b, kind = np.asarray(ds["boundary"].values), np.asarray(ds["boundary_kind"].values)
    for code in (1, 0):
        style = CROSSING_STYLE[crossing_kind(code)]
        vals = b[(kind == code) & np.isfinite(b)]
        for j, v in enumerate(vals):
            ax.axvline(v, color=style["color"], ls=style["linestyle"], lw=1.2,
                       label=f"{style['label']} ({name} = {v:.6g})")


def _boundaries_2d(ds, ax, other) -> list:
    """The located crossings as curves, one colour per kind; their legend handles."""
    if "boundary" not in ds:
        return []
    b = ds["boundary"]
    kind = ds["boundary_kind"]
    y = ds.coords[other].values
    handles = []
    for code in (1, 0):
        style = CROSSING_STYLE[crossing_kind(code)]
        vals = np.where(np.asarray(kind.values) == code, np.asarray(b.values), np.nan)
        if vals.ndim > 2:
            vals = vals.reshape(vals.shape[0], -1, vals.shape[-1])[:, 0, :]
        # one curve per crossing index along the lines (NaN where a line has none);
        # the first curve of a kind carries the kind's legend entry
        first = True
        for j in range(vals.shape[1]):
            if np.isfinite(vals[:, j]).any():
                (line,) = ax.plot(vals[:, j], y, lw=1.6, color=style["color"],
                                  ls=style["linestyle"],
                                  label=style["label"] if first else "_nolegend_")
                if first:
                    handles.append(line)
                first = False
    return handles


def _boundaries_across_2d(ds, ax, along, other) -> list:
    """The crossings located along the second axis (``boundary_across``: the edge of the
    stable region seen along ``other`` at each value of ``along``) as marked curves in
    the colours of their kind; their legend handles."""
    if "boundary_across" not in ds or ds["boundary_across"].dims[0] != along:
        return []
    x = ds.coords[along].values
    vals = np.asarray(ds["boundary_across"].values)
    kind = np.asarray(ds["boundary_across_kind"].values)
    if vals.ndim > 2:   # more swept parameters: the first value of the others
        vals = vals.reshape(vals.shape[0], -1, vals.shape[-1])[:, 0, :]
        kind = kind.reshape(kind.shape[0], -1, kind.shape[-1])[:, 0, :]
    handles = []
    for code in (1, 0):
        style = CROSSING_STYLE[crossing_kind(code)]
        picked = np.where(kind == code, vals, np.nan)
        first = True
        for j in range(picked.shape[1]):
            if np.isfinite(picked[:, j]).any():
                (line,) = ax.plot(x, picked[:, j], lw=0.8, color=style["color"],
                                  ls="none", marker="o", ms=3.5, mfc="white",
                                  label=(f"{style['label']} (located along {other})"
                                         if first else "_nolegend_"))
                if first:
                    handles.append(line)
                first = False
    return handles


def _sample_names(ds) -> list:
    return [n for n in ds.coords if ds.coords[n].dims == ("sample",) and n != "sample"]


#: Energy errors below this (absolute, in the scene's units) are taken as rounding: about
#: 4500 float64 epsilons, what summing E and the work along a run scatters by for energies
#: of order 1 (the Dataset holds no energy scale; the panel prints the largest error, so a
#: reader with energies far from 1 can judge).
ROUNDING = 1e-12


def plot_ensemble(ds, axes=None):
    """The spread of a simulate study's end states, and its runs' energy errors.

    Parameters
    ----------
    ds : xarray.Dataset
        A simulate study's results.
    axes : pair of matplotlib.axes.Axes, optional
        Where to draw the end states and the energy errors (default: a new Figure's).

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    The rolling disk started with spin w (see the scene): x(1) = R w sin(1) and
    y(1) = R w (1 - cos(1)), i.e. (0.8415, 0.4597) w.

    >>> from nhham import plot_ensemble
    >>> from nhham.study.sweep import sweep
    >>> ds = sweep("tests/study/scenes/disk_start.toml", "simulate", ["w=1,2"],
    ...            workers=1).dataset
    >>> ends, energy = plot_ensemble(ds).axes
    >>> ends.get_xlabel(), ends.get_ylabel(), energy.get_title()
    ('x at t_final', 'y at t_final', 'energy balance of the runs')
    >>> ends.collections[0].get_offsets().round(4).tolist()
    [[0.8415, 0.4597], [1.6829, 0.9194]]
    """
    Figure = pyplot()
    if axes is None:
        fig = Figure(figsize=(9.5, 3.8), layout="constrained")
        axes = fig.subplots(1, 2)
    else:
        fig = axes[0].figure
    done = np.asarray(ds["done"].values, dtype=bool).ravel()
    states = list(ds.coords["state"].values)
    picked = _ensemble_names(ds, states)
    final = ds["final_state"].values.reshape(-1, len(states))[done]
    a, b = states.index(picked[0]), states.index(picked[1]) if len(picked) > 1 else 0
    ok = np.asarray(ds["success"].values, dtype=bool).ravel()[done]
    if ok.any():
        axes[0].scatter(final[ok, a], final[ok, b], s=3, alpha=0.5, color="tab:blue",
                        label=f"{ok.sum()} runs")
    if (~ok).any():
        axes[0].scatter(final[~ok, a], final[~ok, b], s=6, color="tab:red", marker="x",
                        label=f"{(~ok).sum()} failed")
    axes[0].set_xlabel(f"{picked[0]} at t_final")
    axes[0].set_ylabel(f"{picked[1] if len(picked) > 1 else picked[0]} at t_final")
    legend_if_labelled(axes[0], fontsize=8, loc="lower left", bbox_to_anchor=(0.0, 1.0),
                       ncol=2, borderaxespad=0.2)
    err = np.abs(ds["energy_error"].values.ravel()[done])
    _energy_panel(axes[1], err[np.isfinite(err)])
    fig.suptitle(_title(ds), fontsize=9)
    for axis in (axes[0].xaxis, axes[0].yaxis):
        separate_tick_labels(axis)
    return fig


def _ensemble_names(ds, states) -> list:
    """The state names to plot: swept or perturbed ones first, then the coordinates."""
    swept = list(_design_dims(ds)) + _sample_names(ds)
    if "perturbed" in ds.coords:
        swept += [str(n) for n in np.atleast_1d(ds.coords["perturbed"].values)]
    picked = [n for n in dict.fromkeys(swept) if n in states]
    return picked + [n for n in states if n not in picked]


def _energy_panel(ax, err) -> None:
    """A histogram of log10 |energy error| when the errors spread over more than a decade
    above rounding; else the numbers, written in the panel (a histogram of rounding noise,
    or of values within a factor 10, shows nothing a reader can use)."""
    from matplotlib.ticker import MaxNLocator

    ax.set_title("energy balance of the runs", fontsize=9)
    if not err.size:
        _panel_text(ax, "no energy error recorded")
        return
    lo, med, hi = np.min(err), np.median(err), np.max(err)
    n = f"{err.size} run{'s' if err.size > 1 else ''}"
    if hi <= ROUNDING:
        _panel_text(ax, f"|E(t_final) - E(0) - work| at rounding level in all {n}:\n"
                        f"largest {hi:.1e} (below {ROUNDING:.0e})\n"
                        "energy balance holds to rounding")
        return
    if hi <= 10 * max(lo, ROUNDING):
        _panel_text(ax, f"|E(t_final) - E(0) - work|, all {n}:\n"
                        f"{lo:.2e} .. {hi:.2e} (median {med:.2e})\n"
                        "within a factor 10 of each other: no histogram")
        return
    ax.hist(np.log10(np.maximum(err, 1e-300)), bins=min(40, max(5, err.size // 3)),
            color="0.4")
    ax.set_xlabel("log10 |E(t_final) - E(0) - work|")
    ax.set_ylabel("runs")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))   # counts: no 2.5 runs


def _panel_text(ax, text) -> None:
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", fontsize=9)
    ax.set_xticks([])
    ax.set_yticks([])


def plot_cases(ds, ax=None):
    """Each point's case of a classify study: the first ``--over`` across, a legend of the
    cases present (the generic verdict in grey, each case in a colour of its own).

    Parameters
    ----------
    ds : xarray.Dataset
        A classify study's results.
    ax : matplotlib.axes.Axes, optional
        Where to draw (default: the axes of a new Figure).

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    phi = q2' + b q3' with W = diag(a, 1, -1): C = -(1 - b^2), regular at b = 0.5 (the
    generic verdict) and zero at b = 1 (the case b - 1 = 0).

    >>> from nhham import plot_cases
    >>> from nhham.study.sweep import sweep
    >>> ds = sweep("examples/parametric_null_constraint.toml", "classify", ["b=0.5,1.0"],
    ...            workers=1).dataset
    >>> ax, = plot_cases(ds).axes
    >>> ax.get_xlabel(), [text.get_text() for text in ax.get_legend().get_texts()]
    ('b', ['generic', 'case 0: b - 1 = 0'])
    """
    from matplotlib.colors import ListedColormap

    fig, ax = _axes(ax)
    dims = _design_dims(ds)
    case = np.where(np.asarray(ds["done"].values, dtype=bool),
                    np.asarray(ds["case"].values, dtype=float), np.nan)
    present = sorted(int(c) for c in np.unique(case[np.isfinite(case)]))
    if len(dims) >= 2 and dims != ("sample",):
        c = case.reshape(case.shape[0], case.shape[1], -1)[:, :, 0]
        index = np.full(c.shape, np.nan)
        for i, k in enumerate(present):
            index[c == k] = i
        if present:
            ax.pcolormesh(ds.coords[dims[0]].values, ds.coords[dims[1]].values,
                          np.ma.masked_invalid(index.T), shading="nearest", vmin=-0.5,
                          vmax=len(present) - 0.5, rasterized=True,
                          cmap=ListedColormap([case_colour(k) for k in present]))
        ax.set_xlabel(dims[0])
        ax.set_ylabel(dims[1])
    else:
        names = list(dims) if dims != ("sample",) else _sample_names(ds)
        x = ds.coords[names[0]].values
        two = dims == ("sample",) and len(names) > 1
        y = ds.coords[names[1]].values if two else case
        for k in present:
            ax.scatter(x[case == k], y[case == k], s=12, color=case_colour(k))
        ax.set_xlabel(names[0])
        if two:
            ax.set_ylabel(names[1])
        else:
            ax.set_yticks(present, [_case_label(ds, k, short=True) for k in present])
            ax.set_ylabel("case")
    legend_if_labelled(ax, handles=_case_handles(ds, present), fontsize=8, **OUTSIDE_RIGHT)
    ax.set_title(_title(ds), fontsize=9)
    return fig


def _case_label(ds, k, short=False) -> str:
    if k < 0:
        return "generic"
    if short:
        return f"case {k}"
    cases = json.loads(ds.attrs.get("options", "{}")).get("cases") or []
    describe = cases[k].get("describe", "") if k < len(cases) else ""
    if len(describe) > 40:
        describe = describe[:39] + "\N{HORIZONTAL ELLIPSIS}"
    return f"case {k}: {describe}" if describe else f"case {k}"


def _case_handles(ds, present) -> list:
    from matplotlib.patches import Patch

    return [Patch(facecolor=case_colour(k), edgecolor="0.5", label=_case_label(ds, k))
            for k in present]


def _axes(ax):
    if ax is not None:
        return ax.figure, ax
    Figure = pyplot()
    fig = Figure(figsize=(6.4, 4.6))
    return fig, fig.subplots()
