"""The paper's Section 6 on T*Q, above the Lagrangian layer.

Modules: ``legendre`` (Leg, its inverse, transport of functions and forms),
``brackets`` (canonical, bivector and Dirac brackets), ``side`` (H, X_H,
constraints and the projected field on T*Q; the nonholonomic bracket),
``classes`` (the ConstraintClasses result), ``classification`` (first and second
class), ``classes_at_points`` (the split decided at exact points of M_f), ``dirac`` (the
Dirac bracket, the Dirac flow against the projected field), ``crosscheck`` (both sides
through Leg), with ``checks`` (its results), ``comparison`` (its points and the numeric
Lagrangian side) and ``staged`` (the check staged at exact points when C is singular).
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
    "ConstraintClasses": "classes",
    "dirac_bracket": "dirac",
    "dirac_vs_projected": "dirac",
    "cross_check": "crosscheck",
    "CrossCheckReport": "checks",
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
