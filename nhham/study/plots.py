"""Pictures of a study's Dataset (matplotlib, the plot extra).

- :func:`plot_stability_map`: linearize over two parameters: where every eigenvalue has
  Re < 0, with the located boundaries drawn as curves (complex pairs crossing, e.g. a
  bicycle's weave speed; real eigenvalues crossing, its capsize speed); over one
  parameter, the spectral abscissa with the boundaries marked; over samples, the points
  coloured by their verdict.
- :func:`plot_ensemble`: simulate: the spread of the end states (the first two swept or
  perturbed names, or the first two coordinates) and the runs' energy errors.
- :func:`plot_cases`: classify: each point's case.

Each returns a :class:`matplotlib.figure.Figure` made without pyplot (no backend is
chosen here); :func:`plot_study` picks the picture of a Dataset and saves it.
"""

from __future__ import annotations

import json

import numpy as np

from nhham.errors import OptionalDependencyError

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
    """Draw the picture of a study's Dataset (by its kind) and save it to ``path``."""
    what = ds.attrs.get("what")
    fig = {"linearize": plot_stability_map, "simulate": plot_ensemble,
           "classify": plot_cases}[what](ds)
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    return str(path)


def _design_dims(ds) -> tuple:
    return tuple(ds["done"].dims)


def _title(ds) -> str:
    source = ds.attrs.get("scene_source", "")
    return f"{source.rsplit('/', 1)[-1]}: {ds.attrs.get('what', '')}"


def plot_stability_map(ds, ax=None):
    """The stability of a linearize study (see the module docstring)."""
    fig, ax = _axes(ax)
    dims = _design_dims(ds)
    done = np.asarray(ds["done"].values, dtype=bool)
    verdict = np.where(done, np.asarray(ds["verdict"].values, dtype=float), np.nan)
    if dims == ("sample",):
        names = [n for n in ds.coords if ds.coords[n].dims == ("sample",) and n != "sample"]
        x = ds.coords[names[0]].values
        y = ds.coords[names[1]].values if len(names) > 1 else np.zeros_like(x)
        for value, colour, label in ((1, "tab:green", "stable"), (0, "tab:red", "unstable"),
                                     (-1, "0.6", "undecided")):
            pick = verdict == value
            ax.scatter(x[pick], y[pick], s=6, color=colour, label=label)
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1] if len(names) > 1 else "")
        ax.legend(loc="best", fontsize=8)
    elif len(dims) == 1:
        x = ds.coords[dims[0]].values
        ax.plot(x, ds["spectral_abscissa"].values, color="k", lw=1.2,
                label="max Re(eigenvalue)")
        ax.axhline(0.0, color="0.5", lw=0.8)
        ax.fill_between(x, 0, 1, where=verdict == 1, color="tab:green", alpha=0.15,
                        transform=ax.get_xaxis_transform(), label="stable")
        _mark_boundaries_1d(ds, ax)
        ax.set_xlabel(dims[0])
        ax.set_ylabel("max Re(eigenvalue)")
        ax.legend(loc="best", fontsize=8)
    else:
        along = json.loads(ds.attrs.get("options", "{}")).get("along") or dims[0]
        other = next(d for d in dims if d != along)
        stable = ds["verdict"].where(ds["done"]).transpose(other, along, ...)
        if stable.ndim > 2:   # more swept parameters: the first value of the others
            stable = stable.isel({d: 0 for d in stable.dims[2:]})
        X, Y = ds.coords[along].values, ds.coords[other].values
        ax.pcolormesh(X, Y, np.where(stable.values == 1, 1.0, 0.0), cmap="Greens", vmin=0,
                      vmax=2.5, shading="nearest", rasterized=True)
        _boundaries_2d(ds, ax, other)
        ax.set_xlabel(along)
        ax.set_ylabel(other)
        ax.set_xlim(X.min(), X.max())
        ax.set_ylim(Y.min(), Y.max())
        ax.legend(loc="upper right", fontsize=8, title="shaded: stable", title_fontsize=8)
    ax.set_title(_title(ds), fontsize=9)
    return fig


def _mark_boundaries_1d(ds, ax) -> None:
    if "boundary" not in ds:
        return
    b, kind = np.asarray(ds["boundary"].values), np.asarray(ds["boundary_kind"].values)
    for k, style, label in ((1, "--", "complex pair crosses"), (0, ":", "real crosses")):
        vals = b[(kind == k) & np.isfinite(b)]
        for j, v in enumerate(vals):
            ax.axvline(v, color="tab:blue" if k else "tab:orange", ls=style, lw=1,
                       label=label if j == 0 else None)


def _boundaries_2d(ds, ax, other) -> None:
    if "boundary" not in ds:
        return
    b = ds["boundary"]
    kind = ds["boundary_kind"]
    y = ds.coords[other].values
    for k, colour, label in ((1, "tab:blue", "complex pair crosses (weave-like)"),
                             (0, "tab:orange", "real eigenvalue crosses (capsize-like)")):
        vals = np.where(np.asarray(kind.values) == k, np.asarray(b.values), np.nan)
        if vals.ndim > 2:
            vals = vals.reshape(vals.shape[0], -1, vals.shape[-1])[:, 0, :]
        # one curve per crossing index along the lines (NaN where a line has none)
        for j in range(vals.shape[1]):
            if np.isfinite(vals[:, j]).any():
                ax.plot(vals[:, j], y, "-", lw=1.6, color=colour,
                        label=label if j == 0 or not np.isfinite(vals[:, :j]).any() else None)


def plot_ensemble(ds, axes=None):
    """The spread of a simulate study's end states, and its runs' energy errors."""
    Figure = pyplot()
    if axes is None:
        fig = Figure(figsize=(9, 3.8))
        axes = fig.subplots(1, 2)
    else:
        fig = axes[0].figure
    done = np.asarray(ds["done"].values, dtype=bool).ravel()
    states = list(ds.coords["state"].values)
    picked = [n for n in list(ds.coords.get("perturbed", np.array([])).values) if n in states]
    picked += [n for n in states if n not in picked]
    final = ds["final_state"].values.reshape(-1, len(states))[done]
    a, b = states.index(picked[0]), states.index(picked[1]) if len(picked) > 1 else 0
    ok = np.asarray(ds["success"].values, dtype=bool).ravel()[done]
    axes[0].scatter(final[ok, a], final[ok, b], s=3, alpha=0.5, color="tab:blue",
                    label=f"{ok.sum()} runs")
    if (~ok).any():
        axes[0].scatter(final[~ok, a], final[~ok, b], s=6, color="tab:red", marker="x",
                        label=f"{(~ok).sum()} failed")
    axes[0].set_xlabel(f"{picked[0]} at t_final")
    axes[0].set_ylabel(f"{picked[1] if len(picked) > 1 else picked[0]} at t_final")
    axes[0].legend(loc="best", fontsize=8)
    err = np.abs(ds["energy_error"].values.ravel()[done])
    err = err[np.isfinite(err)]
    if err.size:
        axes[1].hist(np.log10(np.maximum(err, 1e-300)), bins=40, color="0.4")
    axes[1].set_xlabel("log10 |E(t_final) - E(0) - work|")
    axes[1].set_ylabel("runs")
    fig.suptitle(_title(ds), fontsize=9)
    return fig


def plot_cases(ds, ax=None):
    """Each point's case of a classify study (-1: the generic verdict)."""
    fig, ax = _axes(ax)
    dims = _design_dims(ds)
    case = np.where(np.asarray(ds["done"].values, dtype=bool),
                    np.asarray(ds["case"].values, dtype=float), np.nan)
    if len(dims) >= 2 and dims != ("sample",):
        c = case.reshape(case.shape[0], case.shape[1], -1)[:, :, 0]
        mesh = ax.pcolormesh(ds.coords[dims[1]].values, ds.coords[dims[0]].values, c,
                             shading="nearest", cmap="tab10", vmin=-1, vmax=9)
        ax.set_xlabel(dims[1])
        ax.set_ylabel(dims[0])
        fig.colorbar(mesh, ax=ax, label="case (-1: generic)")
    else:
        x = (ds.coords[dims[0]].values if dims != ("sample",) else
             ds.coords[[n for n in ds.coords if ds.coords[n].dims == ("sample",)
                        and n != "sample"][0]].values)
        ax.plot(x, case, ".", color="k")
        ax.set_xlabel(dims[0])
        ax.set_ylabel("case (-1: generic)")
    ax.set_title(_title(ds), fontsize=9)
    return fig


def _axes(ax):
    if ax is not None:
        return ax.figure, ax
    Figure = pyplot()
    fig = Figure(figsize=(6.4, 4.6))
    return fig, fig.subplots()
