"""The kinds of study, as data: one record each, in :data:`KINDS`.

A kind says what a study computes at every point and how: the module that prepares,
describes, evaluates and summarises it (each module has the same functions:
``prepare(scene, model, design, *, along, run_options, policy)``, ``variables(design,
options)``, ``evaluate(study, ctx, region, until=None)``, ``summary(ds)``,
``summary_warnings(summary)``, ``summary_rows(summary)``), the system its numeric model
is of, its figure, and the options it takes. The command line reads this module before
anything else is imported: constants and a frozen record only.

Adding a kind is one entry here plus its module (see DESIGN.md, "Where a change goes").

Examples
--------
>>> from nhham.study.kinds import KINDS, kind_of
>>> tuple(KINDS)
('linearize', 'simulate', 'classify')
>>> kind_of("linearize").module, kind_of("linearize").along
('nhham.study.stability', True)
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import import_module

from nhham.numerics.methods import names

__all__ = ["StudyKind", "KINDS", "kind_of", "SIMULATE_METHODS"]


@dataclass(frozen=True)
class StudyKind:
    """One kind of study.

    Attributes
    ----------
    name : str
        ``--what NAME``.
    help : str
        What it computes at every point (one line).
    module : str
        The module with its ``prepare``, ``variables``, ``evaluate``, ``summary``,
        ``summary_warnings`` and ``summary_rows``.
    system : {"steady", "closed loop", None}
        What its numeric model is of: the ``[steady]`` system (the loop its ``[control]``
        laws close), the system with its ``[control]`` laws closed, or no model (exact
        work only).
    chunk_points : int
        Points of a chunk by default.
    local : {"threads", "processes"}
        How a local cluster runs its chunks (symbolic work holds the GIL: processes).
    plot : str
        The function of :mod:`nhham.study.plots` that draws it.
    along : bool
        Takes ``--along`` (boundaries traced along a grid dimension).
    perturbations : bool
        Takes ``--initial-perturbation``.
    run_options : tuple of str
        The run's options it takes (``--method``, ``--rtol``...).
    """

    name: str
    help: str
    module: str
    system: str | None
    chunk_points: int
    local: str
    plot: str
    along: bool = False
    perturbations: bool = False
    run_options: tuple = ()

    def load(self):
        """The kind's module (imported on first use)."""
        return import_module(self.module)


#: The kinds, by ``--what`` name.
KINDS = {k.name: k for k in (
    StudyKind("linearize", "the stability of the [steady] motion: eigenvalues, verdict, "
              "boundaries", "nhham.study.stability", "steady", 4096, "threads",
              "plot_stability_map", along=True),
    StudyKind("simulate", "a run from the [initial] state: end state and diagnostics",
              "nhham.study.ensemble", "closed loop", 256, "threads", "plot_ensemble",
              perturbations=True, run_options=("method", "rtol", "atol", "t_end")),
    StudyKind("classify", "the constraint-set verdict", "nhham.study.classes", None, 256,
              "processes", "plot_cases"),
)}

#: The methods of a simulation study (the adaptive ones: each run ends at t_end; the
#: registry :mod:`nhham.numerics.methods` is as light as this module).
SIMULATE_METHODS = names(lambda m: m.adaptive)


def kind_of(name: str) -> StudyKind:
    """The kind called ``name``.

    Raises
    ------
    InputError
        Not a kind (key ``--what``), naming the kinds.
    """
    if name not in KINDS:
        from nhham.errors import InputError

        raise InputError(f"--what: one of {', '.join(KINDS)}, got {name!r}", key="--what")
    return KINDS[name]
