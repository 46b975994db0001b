"""The study's pictures read as they should: legends that say what the tint and the curves
are, one colour per crossing kind (the same in the root locus), only the classify cases
present, the first ``--over`` across, no legend warning when nothing is labelled, and an
energy panel that shows numbers rather than a histogram of noise.

The Datasets are built by hand (a few points, no study run); what each figure must show
is read off the hand-made values.
"""

import json
import warnings
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("matplotlib")
xr = pytest.importorskip("xarray")

from matplotlib.colors import to_rgba  # noqa: E402

from nhham.render.plotting import root_locus_figure  # noqa: E402
from nhham.render.plot_style import GENERIC_COLOUR, case_colour  # noqa: E402
from nhham.study.plots import plot_cases, plot_ensemble, plot_stability_map  # noqa: E402

V = np.array([1.0, 2.0, 3.0, 4.0, 5.0])       # the first --over (along)
C = np.array([0.0, 0.1, 0.2])                 # the second


def linearize_map(verdict, boundary=None, kind=None):
    """A linearize Dataset over (v, c) with the given verdicts (shape (5, 3)) and
    crossings along v (shape (3, k): one row per value of c)."""
    data = {"done": (("v", "c"), np.ones((5, 3), dtype=bool)),
            "verdict": (("v", "c"), np.asarray(verdict, dtype=np.int8)),
            "spectral_abscissa": (("v", "c"), np.zeros((5, 3)))}
    if boundary is not None:
        data["boundary"] = (("c", "crossing"), np.asarray(boundary, dtype=float))
        data["boundary_kind"] = (("c", "crossing"), np.asarray(kind, dtype=np.int8))
    return xr.Dataset(data, coords={"v": V, "c": C},
                      attrs={"what": "linearize", "scene_source": "robot.toml",
                             "options": json.dumps({"along": "v"})})


def legend_texts(ax):
    return [t.get_text() for t in ax.get_legend().get_texts()]


def all_texts(fig):
    out = [fig.texts and fig.texts[0].get_text() or ""]
    for ax in fig.axes:
        out += [t.get_text() for t in ax.texts] + [ax.get_title(), ax.get_xlabel()]
        if ax.get_legend() is not None:
            out += legend_texts(ax)
    return " ".join(out)


# stable for v in 2..3 at every c, undecided at (5, 0.2), unstable elsewhere
VERDICT = np.zeros((5, 3))
VERDICT[1:3, :] = 1
VERDICT[4, 2] = -1
# per line of c: a complex pair crosses at v = 1.5 (into the stable region) and a real
# eigenvalue at v = 3.5 (out of it)
BOUNDARY = [[1.5, 3.5]] * 3
KIND = [[1, 0]] * 3


def cell_colour(fig, v_index, c_index):
    """The colour the map's mesh draws in the cell (v, c)."""
    (mesh,) = fig.axes[0].collections[:1]
    fig.draw_without_rendering()
    colours = mesh.get_facecolors()   # row-major over (c, v): rows are the c values
    return tuple(colours[c_index * len(V) + v_index])


def test_the_legend_names_the_tint_of_each_verdict_and_the_crossings_in_words():
    fig = plot_stability_map(linearize_map(VERDICT, BOUNDARY, KIND))
    ax = fig.axes[0]
    assert legend_texts(ax) == ["stable (every Re < 0)", "unstable (some Re > 0)",
                                "undecided or not linearised",
                                "complex pair crosses the imaginary axis",
                                "real eigenvalue crosses 0"]
    handles = ax.get_legend().legend_handles
    stable, unstable, undecided = (tuple(h.get_facecolor()) for h in handles[:3])
    # the legend's patches are the colours of the cells they name
    assert cell_colour(fig, 1, 0) == stable and cell_colour(fig, 2, 2) == stable
    assert cell_colour(fig, 0, 1) == unstable and cell_colour(fig, 4, 0) == unstable
    assert cell_colour(fig, 4, 2) == undecided
    assert len({stable, unstable, undecided}) == 3
    text = all_texts(fig)
    assert "weave" not in text and "capsize" not in text


def test_one_colour_per_crossing_kind_in_the_map_and_the_root_locus():
    fig = plot_stability_map(linearize_map(VERDICT, BOUNDARY, KIND))
    curves = {ln.get_xdata()[0]: ln for ln in fig.axes[0].get_lines()}
    map_complex, map_real = curves[1.5], curves[3.5]
    swept = SimpleNamespace(
        parameter="v", values=list(V),
        eigenvalues=[np.array([-1.0 + 2j, -1.0 - 2j, -0.5])] * len(V),
        crossings=[SimpleNamespace(kind="complex", value=1.5),
                   SimpleNamespace(kind="real", value=3.5)])
    locus = root_locus_figure(swept, "robot")
    lines = {ln.get_label().split(" (")[0]: ln for ln in locus.axes[0].get_lines()}
    locus_complex = lines["complex pair crosses the imaginary axis"]
    locus_real = lines["real eigenvalue crosses 0"]
    assert to_rgba(locus_complex.get_color()) == to_rgba(map_complex.get_color())
    assert to_rgba(locus_real.get_color()) == to_rgba(map_real.get_color())
    assert to_rgba(map_complex.get_color()) != to_rgba(map_real.get_color())
    assert locus_complex.get_linestyle() == map_complex.get_linestyle()
    assert locus_real.get_linestyle() == map_real.get_linestyle()
    assert [t for t in legend_texts(locus.axes[0]) if "crosses" in t] == [
        "complex pair crosses the imaginary axis (v = 1.5)", "real eigenvalue crosses 0 (v = 3.5)"]


def test_nothing_labelled_no_legend_and_no_warning():
    """A map whose points are all unfinished and crossing-free has nothing to label."""
    ds = linearize_map(VERDICT, [[np.nan, np.nan]] * 3, [[-1, -1]] * 3)
    ds["done"][:] = False
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_stability_map(ds)
    assert fig.axes[0].get_legend() is None


def test_a_map_without_crossings_labels_its_tint_without_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_stability_map(linearize_map(np.ones((5, 3))))
    assert legend_texts(fig.axes[0]) == ["stable (every Re < 0)"]


def test_one_parameter_bands_reach_halfway_to_the_neighbours():
    """v = 1..5 with verdicts unstable, stable, stable, undecided, unstable: the unstable
    bands span 1..1.5 and 4.5..5, the stable one 1.5..3.5 and the undecided one 3.5..4.5
    (midpoints), each verdict once in the legend; the crossing at 1.5 is drawn in its
    kind's words with its value."""
    ds = xr.Dataset({"done": (("v",), np.ones(5, dtype=bool)),
                     "verdict": (("v",), np.array([0, 1, 1, -1, 0], dtype=np.int8)),
                     "spectral_abscissa": (("v",), np.array([1.0, -1, -1, 0, 1])),
                     "boundary": (("crossing",), np.array([1.5, np.nan])),
                     "boundary_kind": (("crossing",), np.array([1, -1], dtype=np.int8))},
                    coords={"v": V}, attrs={"what": "linearize", "options": "{}"})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_stability_map(ds)
    ax = fig.axes[0]
    spans = {p.get_label() for p in ax.patches} - {"_nolegend_"}
    assert spans == {"stable (every Re < 0)", "undecided or not linearised",
                     "unstable (some Re > 0)"}
    bands = sorted((p.get_x(), p.get_x() + p.get_width()) for p in ax.patches)
    assert bands == [pytest.approx((1.0, 1.5)), pytest.approx((1.5, 3.5)),
                     pytest.approx((3.5, 4.5)), pytest.approx((4.5, 5.0))]
    assert "complex pair crosses the imaginary axis (v = 1.5)" in legend_texts(ax)


def classify_map(case, cases):
    return xr.Dataset({"done": (("a", "m"), np.ones(case.shape, dtype=bool)),
                       "case": (("a", "m"), case.astype(np.int16))},
                      coords={"a": np.linspace(-1, 1, case.shape[0]),
                              "m": np.linspace(0, 2, case.shape[1])},
                      attrs={"what": "classify", "scene_source": "robot.toml",
                             "options": json.dumps({"cases": cases})})


CASES = [{"describe": "m = 0"}, {"describe": "4*a**2*m + 1 = 0"}, {"describe": "a = 0"}]


def test_classify_map_generic_everywhere_is_grey_with_no_colour_bar():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_cases(classify_map(np.full((5, 4), -1), CASES))
    assert len(fig.axes) == 1                      # no colour bar of cases 0..8
    ax = fig.axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("a", "m")   # the first --over across
    assert legend_texts(ax) == ["generic"]
    (patch,) = ax.get_legend().legend_handles
    r, g, b, _ = patch.get_facecolor()
    assert r == g == b                             # a neutral grey
    assert all(to_rgba(case_colour(k)) != patch.get_facecolor() for k in range(9))
    fig.draw_without_rendering()
    (mesh,) = ax.collections
    assert {tuple(c) for c in mesh.get_facecolors()} == {to_rgba(GENERIC_COLOUR)}


def test_classify_map_lists_only_the_cases_present():
    case = np.full((5, 4), -1)
    case[2, :] = 2                                 # a = 0 on the whole line
    case[0, 0] = 0
    fig = plot_cases(classify_map(case, CASES))
    ax = fig.axes[0]
    assert legend_texts(ax) == ["generic", "case 0: m = 0", "case 2: a = 0"]
    fig.draw_without_rendering()
    (mesh,) = ax.collections
    colours = mesh.get_facecolors()                # rows over m, columns over a
    assert tuple(colours[0 * 5 + 2]) == to_rgba(case_colour(2))   # (a = 0, m = 0)
    assert tuple(colours[3 * 5 + 2]) == to_rgba(case_colour(2))   # (a = 0, m = 2)
    assert tuple(colours[0 * 5 + 0]) == to_rgba(case_colour(0))   # (a = -1, m = 0)
    assert tuple(colours[1 * 5 + 0]) == to_rgba(GENERIC_COLOUR)


def ensemble(energy_error, over_parameters=True):
    """A simulate Dataset: a grid over two parameters (no swept state, no perturbation)."""
    n = len(energy_error)
    states = ["x", "y", "x_dot", "y_dot"]
    final = np.arange(4.0 * n).reshape(n, 1, 4)
    return xr.Dataset({"done": (("U", "c"), np.ones((n, 1), dtype=bool)),
                       "success": (("U", "c"), np.ones((n, 1), dtype=bool)),
                       "final_state": (("U", "c", "state"), final),
                       "energy_error": (("U", "c"), np.asarray(energy_error).reshape(n, 1))},
                      coords={"U": np.linspace(0.5, 2, n), "c": [0.4], "state": states},
                      attrs={"what": "simulate", "scene_source": "sleigh.toml"})


def test_energy_errors_at_rounding_are_said_in_words_not_drawn():
    errors = np.array([3e-14, -1.2e-13, 2e-16, 8e-14, -5e-15, 1e-13])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_ensemble(ensemble(errors))
    left, right = fig.axes
    assert not right.patches                       # no histogram
    (text,) = right.texts
    assert "rounding level in all 6 runs" in text.get_text()
    assert "1.2e-13" in text.get_text()            # the largest |error|
    # a grid over parameters: the end state's first two coordinates
    assert (left.get_xlabel(), left.get_ylabel()) == ("x at t_final", "y at t_final")


def test_energy_errors_within_a_decade_are_said_in_words():
    errors = np.array([1.11e-10, 1.15e-10, 1.13e-10, 1.12e-10])
    right = plot_ensemble(ensemble(errors)).axes[1]
    assert not right.patches
    assert "1.11e-10 .. 1.15e-10" in right.texts[0].get_text()


def test_energy_errors_that_spread_are_a_histogram_of_every_run():
    errors = np.array([1e-12, 1e-10, 1e-8, 3e-8, 1e-6, 2e-9])
    right = plot_ensemble(ensemble(errors)).axes[1]
    assert not right.texts
    assert sum(p.get_height() for p in right.patches) == len(errors)
    assert right.get_xlabel() == "log10 |E(t_final) - E(0) - work|"
