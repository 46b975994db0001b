"""The kinds of study, and what each takes (constants only: the command line reads them
before anything is imported)."""

__all__ = ["WHAT", "SIMULATE_METHODS"]

#: What a study computes at each point: the stability of the [steady] motion, a run from
#: the [initial] state, the constraint-set verdict.
WHAT = ("linearize", "simulate", "classify")

#: The methods of a simulation study (the adaptive ones: each run ends at t_end).
SIMULATE_METHODS = ("DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA")
