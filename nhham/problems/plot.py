"""The IFToMM maneuvers side by side: roll, steer and energy against t (matplotlib)."""

from __future__ import annotations

__all__ = ["plot_maneuvers"]


def plot_maneuvers(runs):
    """A figure of 3 rows (roll angle, steer angle, E - E_0) and one column a maneuver."""
    from nhham.render.plotting import require_matplotlib

    Figure = require_matplotlib()[0]
    fig = Figure(figsize=(4 * len(runs), 7), layout="constrained")
    axes = fig.subplots(3, len(runs), sharex=True, squeeze=False)
    for j, run in enumerate(runs):
        E = run.columns[:, 5]
        for i, (y, label) in enumerate(((run.columns[:, 0], "roll angle [rad]"),
                                        (run.columns[:, 6], "steer angle [rad]"),
                                        (E - E[0], "E - E_0 [J]"))):
            ax = axes[i][j]
            ax.plot(run.t, y, lw=1)
            ax.set_ylabel(label if j == 0 else "")
            ax.grid(alpha=0.3)
        axes[0][j].set_title(f"{run.name}: v0 = {run.speed:g} m/s, roll rate {run.roll_rate:g}"
                             f" rad/s\nenergy error {run.energy_error_percent:.1e} %",
                             fontsize=9)
        axes[-1][j].set_xlabel("t [s]")
    return fig
