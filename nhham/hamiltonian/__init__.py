"""The paper's Section 6 on T*Q, above the Lagrangian layer.

Modules: ``legendre`` (Leg, its inverse, transport of functions and forms),
``brackets`` (canonical, bivector and Dirac brackets), ``side`` (H, X_H,
constraints and the projected field on T*Q; the nonholonomic bracket),
``classification`` (first and second class, Dirac bracket, Dirac flow
against the projected field), ``crosscheck`` (both sides through Leg).
"""

from nhham.lazy import lazy_exports

_LAZY = {
    "legendre_map": "legendre",
    "LegendreMap": "legendre",
    "canonical_bracket": "brackets",
    "BracketAlgebra": "brackets",
    "hamiltonian_side": "side",
    "HamiltonianSide": "side",
    "nonholonomic_bracket": "side",
    "classify_constraints": "classification",
    "ConstraintClasses": "classification",
    "dirac_bracket": "classification",
    "dirac_vs_projected": "classification",
    "cross_check": "crosscheck",
    "CrossCheckReport": "crosscheck",
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
