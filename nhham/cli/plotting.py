"""Plots of results (matplotlib, an optional extra: ``pip install nhham[plot]``).

matplotlib is imported only when a plot is asked for; without it a
:class:`OptionalDependencyError` says how to install it.
"""

from __future__ import annotations

import numpy as np

from nhham.errors import OptionalDependencyError

__all__ = ["OptionalDependencyError", "plot_work_precision", "plot_trajectory"]


def _pyplot():
    try:
        import matplotlib

        matplotlib.use("Agg")  # files only: never needs a display
        import matplotlib.pyplot as plt
    except ImportError as exc:
        raise OptionalDependencyError(
            "plotting needs matplotlib, an optional extra: pip install 'nhham[plot]' "
            "(or pip install matplotlib)") from exc
    return plt


def plot_work_precision(result, path) -> str:
    """Error at t_end versus wall time, one line per method (log-log); saved to ``path``.

    Parameters
    ----------
    result : WorkPrecisionResult
    path : str or path-like

    Returns
    -------
    str
        The path written.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 5))
    for method in result.methods():
        rows = [r for r in result.rows if r.method == method and r.status == 0
                and np.isfinite(r.error) and r.error > 0]
        if not rows:
            continue
        rows.sort(key=lambda r: r.wall_time_s)
        ax.loglog([r.wall_time_s for r in rows], [r.error for r in rows], "o-", label=method,
                  markersize=3)
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel("relative error at t_end")
    ax.set_title(f"work-precision: {result.name or 'system'}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return str(path)


def plot_trajectory(result, path) -> str:
    """States over time, constraint residual and energy; saved to ``path``.

    Parameters
    ----------
    result : SimulationResult
    path : str or path-like
    """
    plt = _pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    for name, series in zip(result.names, result.y):
        axes[0].plot(result.t, series, label=name, linewidth=1)
    axes[0].legend(fontsize=7, ncol=4)
    axes[0].set_ylabel("state")
    # Exact zeros (at t0, or after projection) would drag a log axis to 1e-300.
    res = np.maximum(result.diagnostics.constraint_residual, 1e-17)
    axes[1].semilogy(result.t, res, linewidth=1)
    axes[1].set_ylabel("max |constraint residual|")
    axes[2].plot(result.t, result.energy - result.energy[0], label="E - E(0)", linewidth=1)
    axes[2].plot(result.t, result.work, "--", label="work of constraint forces", linewidth=1)
    axes[2].legend(fontsize=7)
    axes[2].set_ylabel("energy")
    axes[2].set_xlabel("t")
    axes[0].set_title(f"{result.method}: {result.message}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return str(path)
