"""The kinds of study, and what each takes (constants only: the command line reads them
before anything is imported)."""

from __future__ import annotations

from nhham.numerics.methods import names

__all__ = ["WHAT", "SIMULATE_METHODS"]

#: What a study computes at each point: the stability of the [steady] motion, a run from
#: the [initial] state, the constraint-set verdict.
WHAT = ("linearize", "simulate", "classify")

#: The methods of a simulation study (the adaptive ones: each run ends at t_end; the
#: registry :mod:`nhham.numerics.methods` is as light as this module).
SIMULATE_METHODS = names(lambda m: m.adaptive)
