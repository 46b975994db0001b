"""``--what linearize``: the stability of the scene's steady motion at every point.

At each point the parameters take the point's values, the ``[steady]`` table gives the
steady motion there (its entries are expressions in the parameters) and the inputs'
steady values (with ``[control]`` laws the loop they close is linearised, as ``nhham
linearize`` does), and :func:`~nhham.numerics.batch_linearization.linearize_batch` gives the
state matrix, its eigenvalues and the verdict, in the chart and with the neutral
directions chosen once at probe points (:func:`prepare`). On a grid the crossings of the
imaginary axis along one swept parameter (``along``; the first by default) are located
on every line of the grid, all lines' brackets together
(:func:`~nhham.numerics.crossings.crossings_many`): the stability boundaries, e.g. the
weave and capsize speeds of a bicycle at every trail. On a grid of two or more dimensions
the crossings along its second axis (``across``, the first dimension other than
``along``, recorded in the options) are located as well, on every line along it: the
edge of the stable region where it runs along the first axis, which the lines along
``along`` cross at a grazing angle or not at all. Chunks are slabs that hold whole lines
along ``along`` where they fit, so a line along ``across`` is cut into pieces, each
evaluated with the point before it and merged as written (:mod:`~nhham.study.lines`),
which also holds after ``--resume``.

Variables (``variables``): ``stable`` (every eigenvalue has Re < -tol), ``verdict``
(1 stable, 0 unstable, -1 undecided or not linearised), ``spectral_abscissa`` (max Re),
``eigenvalue_real``/``eigenvalue_imag`` (dimension ``mode``), ``state_matrix`` (``row``,
``column``), ``status`` (0 linearised, 1 not on M_1, 2 not steady (or a ``[control]`` law that does
not give its input's ``[steady]`` value there, which ``nhham linearize`` refuses), 3 singular),
``constraint_residual``, ``acceleration_residual``; on a grid ``boundary`` (the crossing
values along ``along``, dimension ``crossing``, NaN-padded), ``boundary_kind`` (0: a real
eigenvalue through 0, 1: a complex pair through the imaginary axis), ``boundary_direction``
(+1: an eigenvalue's real part turns positive as the value grows), ``boundary_count`` and
``boundary_unlocated`` (intervals of the line where the number of unstable eigenvalues
changes but no eigenvalue is on the imaginary axis: not reported as boundaries); along
the second axis the same five as ``boundary_across``, ``boundary_across_kind``,
``boundary_across_direction``, ``boundary_across_count`` and
``boundary_across_unlocated``, with the grid's dimensions other than ``across``.
"""

from __future__ import annotations


import numpy as np

from nhham.errors import InputError
from nhham.journeys.steady import steady_batch
from nhham.numerics.batch_linearization import ChartChoice
from nhham.study.lines import ACROSS_VARIABLES, LINE_VARIABLES

__all__ = ["prepare", "variables", "evaluate", "summary", "summary_warnings", "summary_rows",
           "across_of", "across_variables", "CROSSINGS", "XTOL"]

#: Room for crossings per line (a line with more keeps the first and says so in
#: ``boundary_count``).
CROSSINGS = 8

#: Absolute tolerance of a located crossing.
XTOL = 1e-12


def prepare(scene, model, design, *, along: str | None = None, run_options=None,
            policy=None) -> dict:
    """The options of a linearize study, decided once: the chart and neutral directions
    (from probes at the first, middle and last points), the parameter slots and the
    boundary dimension.

    Raises
    ------
    InputError
        No ``[steady]`` table, a swept name that is not a parameter (or is an input), an
        ``along`` that is not a grid dimension.
    """
    from nhham.journeys.stability import check_steady_table, symmetry_generator
    from nhham.journeys.steady import sweep_reference

    check_steady_table(scene)
    system = scene.steady_system()
    names = model.parameter_names
    for name in design.names:
        if name in model.input_names:
            raise InputError(f"--over: {name!r} is an input, whose steady value the [steady] "
                             f"table gives; sweep a parameter its entry uses", key="--over")
        if name not in names:
            raise InputError(f"--over: {name!r} is not a parameter of the scene (parameters: "
                             f"{', '.join(n for n in names if n not in model.input_names)})",
                             key="--over")
    if design.kind != "grid":
        along = None
    elif along is None:
        along = design.dims[0]
    elif along not in design.dims:
        raise InputError(f"--along: {along!r} is not swept (swept: {', '.join(design.dims)})",
                         key="--along")
    generator = symmetry_generator(scene, system, model)   # checked once, here
    probes = sorted({0, design.size // 2, design.size - 1})
    points = []
    for flat in probes:
        region = tuple(slice(i, i + 1) for i in np.unravel_index(flat, design.shape))
        points.append({k: float(v.ravel()[0]) for k, v in design.values(region).items()})
    try:
        choice, _ = sweep_reference(scene, system, model, points, generator)
    except InputError as exc:
        raise InputError(f"--what linearize: {exc}".replace("linearize: ", "", 1),
                         key="steady") from None
    options = {"chart": list(choice.chart), "neutral": list(choice.neutral),
               "coordinates": list(choice.coordinates), "along": along,
               "inputs": list(model.input_names),
               "momentum": generator is not None and generator.momentum is not None}
    across = across_of(design, along)
    if across is not None:   # crossings located along the grid's second axis too
        options["across"] = across
    return options


def variables(design, options) -> dict:
    """The variables of a linearize study: ``{"point": {name: (extra dims, dtype, fill)},
    "line": {...}, "coords": {extra dim: its coordinate}}`` ("line": the variables of a
    grid's lines along ``along``, without that dimension)."""
    coords = list(options["coordinates"])
    d = len(coords)
    point = {
        "stable": ((), bool, False),
        "verdict": ((), np.int8, -1),
        "spectral_abscissa": ((), float, np.nan),
        "eigenvalue_real": (("mode",), float, np.nan),
        "eigenvalue_imag": (("mode",), float, np.nan),
        "state_matrix": (("row", "column"), float, np.nan),
        "status": ((), np.int8, -1),
        "constraint_residual": ((), float, np.nan),
        "acceleration_residual": ((), float, np.nan),
    }
    if options["inputs"]:
        point["input_matrix"] = (("row", "input"), float, np.nan)
    extra = {"mode": np.arange(d), "row": coords, "column": coords,
             "input": list(options["inputs"]), "crossing": np.arange(CROSSINGS)}
    lines = {}
    if options["along"] is not None:
        lines = {"boundary": (("crossing",), float, np.nan),
                 "boundary_kind": (("crossing",), np.int8, -1),
                 "boundary_direction": (("crossing",), np.int8, 0),
                 "boundary_count": ((), np.int16, -1),
                 "boundary_unlocated": ((), np.int16, -1)}
    return {"point": point, "line": lines, "across": across_variables(design, options),
            "coords": extra, "attrs": _code_meanings(lines)}


def _code_meanings(lines) -> dict:
    """The meanings of the integer codes (CF's ``flag_values``/``flag_meanings``, and
    each code in words), as the variables' attributes."""
    from nhham.numerics.batch_linearization import STATUS_TEXT
    from nhham.numerics.spectra import VERDICT_TEXT

    def flags(table, names):
        return {"flag_values": list(table), "flag_meanings": " ".join(names),
                "description": "; ".join(f"{k}: {v}" for k, v in table.items())}

    out = {"verdict": flags(VERDICT_TEXT, ["stable", "unstable", "undecided"]),
           "status": flags(STATUS_TEXT, ["linearised", "not_on_M1", "not_steady",
                                         "singular"])}
    kinds = {0: "a real eigenvalue through 0 (divergence)",
             1: "a complex pair through the imaginary axis (flutter, Hopf)",
             -1: "no crossing"}
    directions = {1: "an eigenvalue's real part turns positive as the value grows",
                  -1: "turns negative", 0: "no crossing"}
    for prefix in ("boundary", "boundary_across"):
        out[f"{prefix}_kind"] = flags(kinds, ["real", "complex", "none"])
        out[f"{prefix}_direction"] = flags(directions, ["destabilising", "stabilising",
                                                        "none"])
    return out


def evaluate(study, ctx, region, until: float | None = None) -> dict:
    """Every variable on ``region`` (see the module docstring)."""
    scene, model = ctx.scene, ctx.model
    opts = study.options
    choice = ChartChoice(tuple(opts["chart"]), tuple(opts["neutral"]),
                         tuple(opts["coordinates"]))
    values = study.design.values(region)
    shape = next(iter(values.values())).shape if values else ()
    flat = {k: v.ravel() for k, v in values.items()}
    batch, bad = steady_batch(scene, model, choice, flat, _generator(scene, model, opts))
    status = batch.status
    out = {
        "stable": batch.stable,
        "verdict": batch.verdicts,
        "spectral_abscissa": np.where(bad, np.nan, batch.spectral_abscissa),
        "eigenvalue_real": batch.eigenvalues.real,
        "eigenvalue_imag": batch.eigenvalues.imag,
        "state_matrix": batch.matrices,
        "status": status,
        "constraint_residual": batch.constraint_residuals,
        "acceleration_residual": batch.acceleration_residuals,
    }
    if opts["inputs"]:
        out["input_matrix"] = batch.input_matrices
    out = {k: np.asarray(v).reshape(shape + np.asarray(v).shape[1:]) for k, v in out.items()}
    missing = (batch.status != 0).reshape(shape)
    for k in ("eigenvalue_real", "eigenvalue_imag", "state_matrix"):
        out[k][missing] = np.nan
    if opts["along"] is not None:
        out.update(_boundaries(study, scene, model, choice, region, values, batch, bad))
    return out


def _generator(scene, model, options):
    """The scene's ``[symmetry]`` for the batch (checked by :func:`prepare`, which found
    whether its momentum is conserved)."""
    from nhham.journeys.stability import symmetry_generator

    if scene.symmetry is None:   # (no closed loop built for nothing)
        return None
    return symmetry_generator(scene, scene.steady_system(), model, check=False,
                              conserved=bool(options.get("momentum")))


def _boundaries(study, scene, model, choice, region, values, batch, bad) -> dict:
    """The crossings along ``along`` on every line of the region, located together
    (:class:`~nhham.numerics.crossings.CrossingFinder`: it asks for spectra, this study
    computes them); on a grid of two or more
    dimensions those along ``across`` as well (the ``boundary_across`` variables)."""
    out = _line_crossings(study, scene, model, choice, region, values, batch, bad,
                          study.options["along"], LINE_VARIABLES)
    if study.options.get("across") is not None:
        out.update(_line_crossings(study, scene, model, choice, region, values, batch, bad,
                                   study.options["across"], ACROSS_VARIABLES))
    return out


def across_variables(design, options) -> dict:
    """The variables of the lines along ``across`` (``{}`` without a second axis): those
    of the lines along ``along``, named ``boundary_across...``."""
    if options.get("across") is None:
        return {}
    return dict(zip(ACROSS_VARIABLES, (
        (("crossing",), float, np.nan), (("crossing",), np.int8, -1),
        (("crossing",), np.int8, 0), ((), np.int16, -1), ((), np.int16, -1))))


def across_of(design, along) -> str | None:
    """The second axis of a grid whose crossings are located too: its first dimension
    other than ``along`` (None for one dimension, samples, or no ``along``)."""
    if along is None or design.kind != "grid" or len(design.dims) < 2:
        return None
    return next(d for d in design.dims if d != along)


def _line_crossings(study, scene, model, choice, region, values, batch, bad, axis_name,
                    names) -> dict:
    """The crossings along ``axis_name`` on every line of the region, as the variables
    ``names`` (:data:`~nhham.study.lines.LINE_VARIABLES` or ``ACROSS_VARIABLES``)."""
    from nhham.numerics.crossings import CrossingFinder

    dims = study.design.dims
    a = dims.index(axis_name)
    shape = tuple(len(range(*s.indices(n))) for s, n in zip(region, study.design.shape))
    along_values = values[dims[a]]
    rest = shape[:a] + shape[a + 1:]
    index = np.arange(int(np.prod(shape))).reshape(shape)
    # the unstable eigenvalues counted for the whole chunk at once; a spectrum is made
    # only where a line's count changes (the search reads nothing else)
    counts = batch.unstable_counts
    lines, fixed, line_counts = [], [], []
    for line in np.ndindex(*rest):
        at = line[:a] + (slice(None),) + line[a:]
        lines.append((along_values[at], _Spectra(batch, bad, index[at])))
        line_counts.append(counts[index[at]].tolist())
        fixed.append({k: float(v[at][0]) for k, v in values.items() if k != dims[a]})

    # the finder asks for spectra; this study computes them in batches of its own
    finder = CrossingFinder(lines, xtol=XTOL, counts=line_counts)
    while finder.requests:
        points = {k: np.array([dict(fixed[line], **{dims[a]: x})[k]
                               for line, x in finder.requests]) for k in values}
        finder.supply(_spectra(study, scene, model, choice, points))
    search = finder.result()
    value, kind, direction, count, unlocated_count = names
    out = {value: np.full(rest + (CROSSINGS,), np.nan),
           kind: np.full(rest + (CROSSINGS,), -1, dtype=np.int8),
           direction: np.zeros(rest + (CROSSINGS,), dtype=np.int8),
           count: np.zeros(rest, dtype=np.int16),
           unlocated_count: np.zeros(rest, dtype=np.int16)}
    for line, crossings, unlocated in zip(np.ndindex(*rest), search.crossings,
                                          search.unlocated):
        out[count][line] = len(crossings)
        out[unlocated_count][line] = len(unlocated)
        for j, c in enumerate(crossings[:CROSSINGS]):
            out[value][line + (j,)] = c.value
            out[kind][line + (j,)] = 0 if c.kind == "real" else 1
            out[direction][line + (j,)] = c.direction
    return out


class _Spectra:
    """The spectra of some states of a batch, made when read."""

    def __init__(self, batch, bad, index):
        self.batch, self.bad, self.index = batch, bad, index

    def __len__(self):
        return len(self.index)

    def __getitem__(self, i):
        j = self.index[i]
        return None if self.bad[j] else self.batch.spectrum(j)


def _spectra(study, scene, model, choice, points) -> list:
    """The spectra at many points (``points``: swept name -> values), None where there is
    no linearisation."""
    batch, _ = steady_batch(scene, model, choice, points,
                            _generator(scene, model, study.options))
    return [batch.spectrum(i) for i in range(batch.status.size)]


def summary(ds) -> dict:
    """What the study found, in a few numbers (JSON-ready): stable and unlinearised
    points, the crossings of each kind and their range, the unlocated ones (along the
    grid's second axis too, ``across_...``)."""
    import json

    done = np.asarray(ds["done"].values, dtype=bool)
    stable = np.asarray(ds["stable"].values, dtype=bool) & done
    status = np.asarray(ds["status"].values)
    out: dict = {"stable_points": int(stable.sum()), "done_points": int(done.sum()),
                 "not_linearised": int(((status != 0) & done).sum())}
    if "boundary" in ds:
        out.update(_crossings(ds, "boundary", ""))
    if "boundary_across" in ds:   # along the grid's second axis
        out["across"] = json.loads(ds.attrs.get("options", "{}")).get("across")
        out.update(_crossings(ds, "boundary_across", "across_"))
    return out


def _crossings(ds, variable: str, prefix: str) -> dict:
    """The located crossings of ``variable`` (and its ``_kind``, ``_unlocated``) by kind:
    their number and range, and the intervals with no crossing located."""
    out: dict = {}
    b = np.asarray(ds[variable].values)
    kinds = np.asarray(ds[f"{variable}_kind"].values)
    for kind, name in ((0, "real"), (1, "complex")):
        vals = b[(kinds == kind) & np.isfinite(b)]
        out[f"{prefix}{name}_crossings"] = int(vals.size)
        out[f"{prefix}{name}_crossing_range"] = ([float(vals.min()), float(vals.max())]
                                                 if vals.size else None)
    unlocated = np.asarray(ds[f"{variable}_unlocated"].values)
    out[f"{prefix}unlocated_crossings"] = int(unlocated[unlocated > 0].sum())
    return out


def summary_warnings(s: dict) -> list:
    """The warnings a summary calls for (one line each)."""
    out = []
    if s["not_linearised"]:
        out.append(f"{s['not_linearised']} points have no linearisation: the [steady] "
                   f"state is not on M_1, not steady or singular there (status in the "
                   f"results: 1, 2, 3)")
    if s.get("across_unlocated_crossings"):
        out.append(f"{s['across_unlocated_crossings']} grid intervals along {s['across']} "
                   f"change their number of unstable eigenvalues with no eigenvalue on "
                   f"the imaginary axis: no boundary is reported there "
                   f"(boundary_across_unlocated in the results)")
    if s.get("unlocated_crossings"):
        out.append(f"{s['unlocated_crossings']} grid intervals along the boundaries' "
                   f"parameter change their number of unstable eigenvalues with no "
                   f"eigenvalue on the imaginary axis (a jump of the linearisation): no "
                   f"boundary is reported there (boundary_unlocated in the results)")
    return out


def summary_rows(s: dict) -> list:
    """(label, text) rows of the command's report."""
    from nhham.render.plot_style import CROSSING_STYLE

    rows = [("stable", f"{s['stable_points']} of {s['done_points']} points"
             + (f"; {s['not_linearised']} not linearised (status != 0)"
                if s["not_linearised"] else ""))]
    for prefix, where in (("", ""), ("across_", f" along {s.get('across')}")):
        for kind in ("complex", "real"):
            word = CROSSING_STYLE[kind]["label"]
            if s.get(f"{prefix}{kind}_crossings"):
                lo, hi = s[f"{prefix}{kind}_crossing_range"]
                rows.append((f"{kind} crossings{where}",
                             f"{s[f'{prefix}{kind}_crossings']}, {word}, "
                             f"{lo:.6g} .. {hi:.6g}"))
    return rows
