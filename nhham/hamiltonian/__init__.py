"""The paper's Section 6 on T*Q, above the Lagrangian layer.

Modules: ``legendre`` (Leg, its inverse, transport of functions and forms),
``brackets`` (canonical, bivector and Dirac brackets), ``side`` (H, X_H,
constraints and the projected field on T*Q), ``almost_poisson`` (the nonholonomic
bracket and its Jacobiator),
``classes`` (the ConstraintClasses result), ``classification`` (first and second
class), ``classes_at_points`` (the split decided at exact points of M_f), ``dirac`` (the
Dirac bracket, the Dirac flow against the projected field), ``crosscheck`` (both sides
through Leg), with ``checks`` (its results), ``comparison`` (its points and the numeric
Lagrangian side) and ``staged`` (the check staged at exact points when C is singular).
"""

from nhham.lazy import by_module, lazy_exports

_LAZY = by_module({
    "legendre": ("legendre_map", "LegendreMap"),
    "brackets": ("canonical_bracket", "BracketAlgebra"),
    "side": ("hamiltonian_side", "HamiltonianSide"),
    "almost_poisson": ("nonholonomic_bracket", "NonholonomicBracket", "JacobiatorReport"),
    "classification": ("classify_constraints",),
    "classes": ("ConstraintClasses",),
    "dirac": ("dirac_bracket", "dirac_vs_projected"),
    "crosscheck": ("cross_check",),
    "checks": ("CrossCheckReport",),
})
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
