"""Figures: a panel per kind, honest data, distinguishable series, no backend chosen."""

import subprocess
import sys
import warnings

import numpy as np
import pytest

pytest.importorskip("matplotlib")

import nhham  # noqa: E402
from nhham.render.plotting import plot_trajectory, plot_work_precision, series_styles  # noqa: E402
from nhham.numerics.workprecision import WorkPrecisionResult, WorkPrecisionRow  # noqa: E402

from conftest import EXAMPLES  # noqa: E402


@pytest.fixture(scope="module")
def disk_run():
    scene = nhham.load_scene(EXAMPLES / "rolling_disk.toml")
    return nhham.simulate(scene.system, **scene.simulate_options(t_end=2.0, method="rattle",
                                                                  step=0.01))


def test_trajectory_has_a_panel_per_kind(disk_run):
    fig = plot_trajectory(disk_run, title="vertical rolling disk")
    axes = fig.axes
    assert [ax.get_ylabel() for ax in axes] == [
        "coordinates q", "velocities dq/dt", "max |constraint\nresidual|", "energy change"]
    assert fig._suptitle.get_text() == "vertical rolling disk"
    assert [t.get_text() for t in axes[0].get_legend().get_texts()] == ["x", "y", "theta", "phi"]
    assert [t.get_text() for t in axes[1].get_legend().get_texts()] == [
        "x_dot", "y_dot", "theta_dot", "phi_dot"]
    # The data drawn are the run's own: no clamped fake residual at t = 0.
    (line,) = axes[2].get_lines()
    drawn = np.asarray(line.get_ydata(), dtype=float)
    res = disk_run.diagnostics.constraint_residual
    assert np.all(np.isnan(drawn[res == 0])) and np.allclose(drawn[res > 0], res[res > 0])
    x = axes[0].get_lines()[0]
    assert np.array_equal(x.get_xdata(), disk_run.t) and np.array_equal(x.get_ydata(),
                                                                         disk_run["x"])


def test_trajectory_draws_into_given_axes(disk_run):
    from matplotlib.figure import Figure

    fig = Figure()
    axes = fig.subplots(2, 2).ravel()
    assert plot_trajectory(disk_run, axes=axes) is fig
    with pytest.raises(ValueError):
        plot_trajectory(disk_run, axes=axes[:2])


def test_more_than_ten_series_stay_distinguishable():
    styles = series_styles(25)
    keys = {(s["color"], s["marker"], s["linestyle"]) for s in styles}
    assert len(keys) == 25


def _row(method, setting, error, wall):
    return WorkPrecisionRow(method, setting, error, wall, 100, 1e-12, 1e-10, 1e-10, 0)


def test_work_precision_lines_in_tolerance_order_one_colour_per_method():
    """Runs listed out of order, with wall times that do not follow the tolerance:
    each line still joins the runs from the loosest to the tightest setting."""
    rows = [_row("DOP853", "rtol=1e-08", 1e-9, 0.002), _row("DOP853", "rtol=1e-04", 1e-5, 0.003),
            _row("DOP853", "rtol=1e-06", 1e-7, 0.001),
            _row("DOP853+projection", "rtol=1e-06", 2e-7, 0.002),
            _row("DOP853+projection", "rtol=1e-04", 2e-5, 0.001),
            _row("rattle", "h=0.1", 1e-3, 0.001), _row("rattle", "h=0.01", 1e-5, 0.01),
            WorkPrecisionRow("rk4", "h=0.1", float("nan"), 0.001, 1, 1, 1, 1, -2)]
    result = WorkPrecisionResult(tuple(rows), "test", (0.0, 1.0), 30, 1e-30, 0.1, "numpy")
    fig = plot_work_precision(result)
    (ax,) = fig.axes
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    assert set(lines) == {"DOP853", "DOP853+projection", "rattle"}  # failed rk4 not drawn
    assert list(lines["DOP853"].get_ydata()) == [1e-5, 1e-7, 1e-9]
    assert list(lines["rattle"].get_ydata()) == [1e-3, 1e-5]
    assert lines["DOP853"].get_color() == lines["DOP853+projection"].get_color()
    assert lines["DOP853+projection"].get_linestyle() == "--"
    assert lines["DOP853"].get_color() != lines["rattle"].get_color()


def test_plotting_never_chooses_the_backend():
    code = ("import matplotlib, sys; b = matplotlib.get_backend(); "
            "import nhham.render.plotting as p; from nhham.cli.main import main; "
            "print(matplotlib.get_backend() == b, 'matplotlib.pyplot' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env={"MPLBACKEND": "svg", "PATH": ""}).stdout.split()
    assert out == ["True", "False"]


def test_simulate_plot_option_writes_the_figure(tmp_path):
    from conftest import run_inprocess

    path = tmp_path / "disk.png"
    rc, out, err = run_inprocess("simulate", str(EXAMPLES / "rolling_disk.toml"), "--t-end", "1",
                                 "--plot", str(path), "--json")
    assert rc == 0, err
    assert path.stat().st_size > 10_000 and path.read_bytes()[:4] == b"\x89PNG"


def _inside(inner, outer) -> bool:
    return inner.x0 < outer.x1 and inner.x1 > outer.x0 and inner.y0 < outer.y1 and \
        inner.y1 > outer.y0


def test_trajectory_legends_sit_off_the_data(disk_run):
    """Each legend lies right of its panel: no legend box meets an axes box."""
    fig = plot_trajectory(disk_run)
    fig.draw_without_rendering()
    panels = [ax.get_window_extent() for ax in fig.axes]
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    assert len(legends) == 3          # coordinates, velocities, energy
    for legend in legends:
        box = legend.get_window_extent()
        assert not any(_inside(box, panel) for panel in panels)


def _narrow_rows(lo, hi):
    """One method whose runs take lo .. hi seconds (four settings, geometric)."""
    return [_row("DOP853", f"rtol=1e-{2 * k + 4:02d}", 10.0 ** (-2 * k - 4), w)
            for k, w in enumerate(np.geomspace(lo, hi, 4))]


@pytest.mark.parametrize("lo, hi", [(1.1e-4, 1.4e-4), (1.2e-4, 1.5e-3), (1e-5, 10.0)])
def test_work_precision_time_labels_never_overlap(lo, hi):
    """matplotlib's default labels every minor tick of a short log span (2x10^-4,
    3x10^-4, 4x10^-4, ...): at 4 inches wide those of 1.2e-4 .. 1.5e-3 s collide."""
    from matplotlib.figure import Figure

    from nhham.render.plot_style import drawn_tick_labels, labels_overlap

    fig = Figure(figsize=(4, 3), layout="constrained")
    ax = fig.subplots()
    result = WorkPrecisionResult(tuple(_narrow_rows(lo, hi)), "t", (0.0, 1.0), 30, 1e-30,
                                 0.1, "numpy")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        plot_work_precision(result, ax=ax)
    assert not labels_overlap(ax.xaxis)
    assert len(drawn_tick_labels(ax.xaxis)) >= 2      # still read off the axis


def test_the_overlap_check_sees_labels_that_collide():
    """The check the test above relies on: ten long labels on a narrow axis collide."""
    from matplotlib.figure import Figure

    from nhham.render.plot_style import labels_overlap, separate_tick_labels

    fig = Figure(figsize=(3, 2))
    ax = fig.subplots()
    ax.set_xticks(range(10), [f"label {k}" for k in range(10)])
    assert labels_overlap(ax.xaxis)
    separate_tick_labels(ax.xaxis)
    assert not labels_overlap(ax.xaxis)


def test_no_legend_and_no_warning_when_nothing_is_labelled():
    """Every run failed: nothing drawn, nothing labelled, no "No artists with labels"."""
    rows = [WorkPrecisionRow("rk4", "h=0.1", float("nan"), 0.001, 1, 1, 1, 1, -2)]
    result = WorkPrecisionResult(tuple(rows), "t", (0.0, 1.0), 30, 1e-30, 0.1, "numpy")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_work_precision(result)
    assert fig.axes[0].get_legend() is None


def test_work_precision_legend_off_the_data_and_no_projection_title_without_variants():
    rows = [_row("DOP853", "rtol=1e-04", 1e-5, 0.003), _row("DOP853", "rtol=1e-06", 1e-7, 0.01),
            _row("rattle", "h=0.1", 1e-3, 0.001)]
    fig = plot_work_precision(WorkPrecisionResult(tuple(rows), "t", (0.0, 1.0), 30, 1e-30,
                                                  0.1, "numpy"))
    (ax,) = fig.axes
    fig.draw_without_rendering()
    legend = ax.get_legend()
    assert not _inside(legend.get_window_extent(), ax.get_window_extent())
    assert legend.get_title().get_text() == ""     # no dashed lines to explain


def test_the_gallery_s_work_precision_times_are_medians_over_passes():
    """bench/work_precision_figure.py: each setting's time is the median of its passes
    (three passes with one loaded: 5, 1, 2 ms -> 2 ms), the other columns the first's."""
    import importlib.util

    from conftest import ROOT

    spec = importlib.util.spec_from_file_location(
        "work_precision_figure", ROOT / "bench" / "work_precision_figure.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    passes = []
    for loose, tight in ((0.005, 0.004), (0.001, 0.003), (0.002, 0.0035)):
        rows = (_row("DOP853", "rtol=1e-04", 1e-5, loose), _row("DOP853", "rtol=1e-06", 1e-7, tight))
        passes.append(WorkPrecisionResult(rows, "t", (0.0, 1.0), 30, 1e-30, 0.1, "numpy"))
    merged, times = module.median_of_passes(passes)
    assert [r.wall_time_s for r in merged.rows] == [0.002, 0.0035]
    assert [r.error for r in merged.rows] == [1e-5, 1e-7]
    assert times[("DOP853", "rtol=1e-04")] == [0.005, 0.001, 0.002]
