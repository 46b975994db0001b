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
``column``), ``status`` (0 linearised, 1 not on M_1, 2 not steady, 3 singular),
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

from nhham.errors import ComputationError, InputError
from nhham.numerics.batch_linearization import ChartChoice, linearize_batch
from nhham.study.lines import ACROSS_VARIABLES, LINE_VARIABLES

__all__ = ["prepare", "variables", "evaluate", "across_of", "across_variables", "CROSSINGS",
           "XTOL"]

#: Room for crossings per line (a line with more keeps the first and says so in
#: ``boundary_count``).
CROSSINGS = 8

#: Absolute tolerance of a located crossing.
XTOL = 1e-12


def prepare(scene, model, design, along: str | None = None) -> dict:
    """The options of a linearize study, decided once: the chart and neutral directions
    (from probes at the first, middle and last points), the parameter slots and the
    boundary dimension.

    Raises
    ------
    InputError
        No ``[steady]`` table, a swept name that is not a parameter (or is an input), an
        ``along`` that is not a grid dimension.
    """
    from nhham.numerics.linearization import linearize
    from nhham.numerics.steady_sweep import steady_state

    if scene.steady is None:
        raise InputError(f"{scene.source}: --what linearize needs a [steady] table (a value, "
                         f"or an expression in the parameters, for every coordinate and "
                         f"velocity)", key="steady")
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
    probes = sorted({0, design.size // 2, design.size - 1})
    found: list = []
    problems: list = []
    for flat in probes:
        region = tuple(slice(i, i + 1) for i in np.unravel_index(flat, design.shape))
        params = {k: float(v.ravel()[0]) for k, v in design.values(region).items()}
        m = model.with_parameters(**params)
        try:
            chart = found[0][3].chart if found else None
            m, state = steady_state(m, scene.steady.values(m.parameters), chart, warn=False)
            family = scene.steady.family(m.parameters)
            found.append((m, state, family, linearize(m, state, independent=chart,
                                                      family=family)))
        except (InputError, ComputationError) as exc:
            problems.append(f"at {params}: {exc}")
    if not found:
        raise InputError("--what linearize: the [steady] motion is not steady (or not on M_1) "
                         "at any probe point: " + "; ".join(problems), key="steady")
    # One chart and the directions neutral at every probe (a direction can be neutral
    # at an isolated value only, e.g. the yaw rate of a disc at rest).
    m, state, family, lin = found[0]
    common = [s for s in lin.neutral if all(s in f[3].neutral for f in found)]
    if len(common) != len(lin.neutral):
        # a family tangent divided out at every probe only (the sleigh's speed at U = 0
        # is in A's kernel, at no other U)
        family = {p: t for p, t in (family or {}).items() if f"d/d{p}" in common}
        lin = linearize(m, state, independent=lin.chart, family=family or None,
                        neutral=[s for s in common if not s.startswith("d/d")])
    choice = ChartChoice.of(lin)
    return {"chart": list(choice.chart), "neutral": list(choice.neutral),
            "coordinates": list(choice.coordinates), "along": along,
            "inputs": list(model.input_names)}


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
            "coords": extra}


def evaluate(study, ctx, region) -> dict:
    """Every variable on ``region`` (see the module docstring)."""
    scene, model = ctx.scene, ctx.model
    opts = study.options
    choice = ChartChoice(tuple(opts["chart"]), tuple(opts["neutral"]),
                         tuple(opts["coordinates"]))
    values = study.design.values(region)
    shape = next(iter(values.values())).shape if values else ()
    flat = {k: v.ravel() for k, v in values.items()}
    Y, P, bad = _states(scene, model, flat)
    batch = linearize_batch(model, Y, P, reference=choice,
                            families=_families(scene, model, P, choice))
    status = batch.status.copy()
    status[bad] = 1
    out = {
        "stable": batch.stable & ~bad,
        "verdict": np.where(bad, -1, batch.verdicts).astype(np.int8),
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
    missing = (bad | (batch.status != 0)).reshape(shape)
    for k in ("eigenvalue_real", "eigenvalue_imag", "state_matrix"):
        out[k][missing] = np.nan
    if opts["along"] is not None:
        out.update(_boundaries(study, scene, model, choice, region, values, batch, bad))
    return out


def _states(scene, model, flat) -> tuple:
    """(Y (N, 2n), P (N, parameters), bad (N,)): the steady states and parameters at the
    points (``flat``: swept name -> values); bad where an entry of [steady] is not a
    finite real number there."""
    names = model.parameter_names
    N = len(next(iter(flat.values()))) if flat else 1
    P = np.tile(np.asarray(model.parameter_values, dtype=float), (N, 1))
    for k, v in flat.items():
        P[:, names.index(k)] = v
    params = {k: P[:, i] for i, k in enumerate(names)}
    steady = scene.steady.arrays(params)
    for u in model.input_names:
        if u in steady:
            P[:, names.index(u)] = steady[u]
    Y = np.column_stack([steady[s] for s in model.names])
    bad = ~np.isfinite(Y).all(axis=1) | ~np.isfinite(P).all(axis=1)
    Y[bad] = 0.0
    P[bad] = np.where(np.isfinite(P[bad]), P[bad], 0.0)
    return Y, P, bad


def _families(scene, model, P, choice):
    """Each point's tangents of the steady family, where the chart divides one out."""
    if not any(s.startswith("d/d") for s in choice.neutral):
        return None
    names = model.parameter_names
    return [scene.steady.family(dict(zip(names, p))) for p in P]


def _boundaries(study, scene, model, choice, region, values, batch, bad) -> dict:
    """The crossings along ``along`` on every line of the region, located together
    (:func:`~nhham.numerics.crossings.crossings_many`); on a grid of two or more
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
    from nhham.numerics.crossings import crossings_many

    dims = study.design.dims
    a = dims.index(axis_name)
    shape = tuple(len(range(*s.indices(n))) for s, n in zip(region, study.design.shape))
    along_values = values[dims[a]]
    rest = shape[:a] + shape[a + 1:]
    index = np.arange(int(np.prod(shape))).reshape(shape)
    # the unstable eigenvalues counted for the whole chunk at once; a spectrum is made
    # only where a line's count changes (the search reads nothing else)
    with np.errstate(invalid="ignore"):
        positive = (batch.eigenvalues.real > batch.tolerances[:, None]).sum(axis=1)
    counts = np.where(bad | (batch.status != 0), -1, positive)
    lines, fixed, line_counts = [], [], []
    for line in np.ndindex(*rest):
        at = line[:a] + (slice(None),) + line[a:]
        lines.append((along_values[at], _Spectra(batch, bad, index[at])))
        line_counts.append(counts[index[at]].tolist())
        fixed.append({k: float(v[at][0]) for k, v in values.items() if k != dims[a]})

    def spectra_at(requests):
        points = {k: np.array([dict(fixed[line], **{dims[a]: x})[k] for line, x in requests])
                  for k in values}
        return _spectra(scene, model, choice, points)

    search = crossings_many(spectra_at, lines, xtol=XTOL, counts=line_counts)
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


def _spectra(scene, model, choice, points) -> list:
    """The spectra at many points (``points``: swept name -> values), None where there is
    no linearisation."""
    Y, P, bad = _states(scene, model, points)
    batch = linearize_batch(model, Y, P, reference=choice,
                            families=_families(scene, model, P, choice))
    return [None if bad[i] else batch.spectrum(i) for i in range(len(Y))]


