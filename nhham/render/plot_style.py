"""The words and colours every nhham figure shares (no matplotlib import here).

A crossing of the imaginary axis is drawn in one colour per kind in the root locus of
``nhham linearize --sweep --plot`` and in the stability maps of ``nhham sweep --what
linearize``; the verdicts of a linearisation and the classify cases have one colour each
wherever they appear. The study layer holds the table so that both the study's pictures
and the command's (the layer above) read it.

:func:`legend_if_labelled` draws a legend only when something on the axes carries a
label (matplotlib warns "No artists with labels found to put in legend" otherwise);
:func:`separate_tick_labels` thins an axis's ticks until no two labels overlap as drawn.
"""

from __future__ import annotations

__all__ = ["CROSSING_STYLE", "VERDICT_STYLE", "GENERIC_COLOUR", "case_colour",
           "crossing_kind", "legend_if_labelled", "OUTSIDE_RIGHT", "drawn_tick_labels",
           "labels_overlap", "separate_tick_labels"]

#: Per kind of crossing (``"complex"``: a complex pair; ``"real"``: a real eigenvalue):
#: its colour, line style and the words of its legend entry.
CROSSING_STYLE = {
    "complex": {"color": "tab:blue", "linestyle": "-",
                "label": "complex pair crosses the imaginary axis"},
    "real": {"color": "tab:orange", "linestyle": "--",
             "label": "real eigenvalue crosses 0"},
}

#: Per verdict of a linearisation (1 stable, 0 unstable, -1 undecided or not
#: linearised): the tint of a map's cells (``fill``), the colour of a point (``color``,
#: the same hue, darker) and the words of its legend entry.
VERDICT_STYLE = {
    1: {"fill": "#b7e2b1", "color": "tab:green", "label": "stable (every Re < 0)"},
    0: {"fill": "#fcd0c0", "color": "tab:red", "label": "unstable (some Re > 0)"},
    -1: {"fill": "0.7", "color": "0.45", "label": "undecided or not linearised"},
}

#: The generic verdict of a classify study (no exceptional case holds): a neutral grey,
#: never one of the cases' colours.
GENERIC_COLOUR = "0.82"

#: Keyword arguments of ``ax.legend`` that put it to the right of the axes, off the data.
OUTSIDE_RIGHT = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "borderaxespad": 0.0}

_CASE_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
                 "tab:pink", "tab:olive", "tab:cyan")


def case_colour(case: int) -> str:
    """The colour of classify case ``case`` (``-1``: the generic verdict, grey).

    The cases take matplotlib's tab10 colours without its grey, so no case looks
    like the generic verdict; beyond nine they repeat.
    """
    if case < 0:
        return GENERIC_COLOUR
    return _CASE_COLOURS[case % len(_CASE_COLOURS)]


def crossing_kind(code) -> str:
    """``"complex"`` or ``"real"`` from a study's ``boundary_kind`` code (1, 0) or a name."""
    if isinstance(code, str):
        return code
    return "complex" if int(code) == 1 else "real"


def legend_if_labelled(ax, **kwargs):
    """``ax.legend(**kwargs)`` when there is something to label; else None (no warning).

    Something to label: the ``handles`` given, or else an artist on ``ax`` with a label.
    """
    handles = kwargs.get("handles")
    if handles is None:
        handles, _ = ax.get_legend_handles_labels()
    if not len(handles):
        return None
    return ax.legend(**kwargs)


def drawn_tick_labels(axis) -> list:
    """``(position, window extent)`` of the tick labels ``axis`` draws (non-empty, in the
    view), in order along the axis; lays the figure out first."""
    axis.figure.draw_without_rendering()
    lo, hi = sorted(axis.get_view_interval())
    out = []
    for tick in axis.get_major_ticks() + axis.get_minor_ticks():
        label = tick.label1
        if (label.get_visible() and label.get_text() and tick.get_visible()
                and lo <= tick.get_loc() <= hi):
            out.append((tick.get_loc(), label.get_window_extent()))
    return sorted(out, key=lambda item: item[0])


def labels_overlap(axis) -> bool:
    """Whether two neighbouring tick labels of ``axis`` overlap as drawn."""
    return _overlap(drawn_tick_labels(axis), axis.axis_name == "x")


def _overlap(drawn, horizontal) -> bool:
    boxes = [box for _, box in drawn]
    return any((a.x1 > b.x0 if horizontal else a.y1 > b.y0) for a, b in zip(boxes, boxes[1:]))


def separate_tick_labels(axis, rounds: int = 4) -> None:
    """Keep every second labelled tick (then every fourth, ...) until no two labels of
    ``axis`` overlap at the figure's size (the kept ones become the major ticks, the minor
    ticks lose their labels)."""
    from matplotlib.ticker import FixedLocator, NullFormatter

    for _ in range(rounds):
        drawn = drawn_tick_labels(axis)
        if not _overlap(drawn, axis.axis_name == "x"):
            return
        axis.set_major_locator(FixedLocator([loc for loc, _ in drawn][::2]))
        axis.set_minor_formatter(NullFormatter())
