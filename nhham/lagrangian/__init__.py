"""The paper on TQ (Sections 2-5): the exact geometry layer.

Modules: ``domains``, ``linalg`` and ``formulas`` (the arithmetics, their linear
algebra, and the paper's formulas at a point written once for all of them),
``points`` (exact points of M_k), ``engine`` (:func:`decide`, the one cascade of every
decision, and the :class:`Policy` it follows), ``quantities`` (rank and vanishing),
``submanifold`` (M_k: its reduction and its float points), with a :class:`Decision`
(``decision``) recording how each answer was reached; ``sampled`` at float points),
``geometry`` (E_L, omega_L, xi_L, Z_i, C, P(xi_L)), ``algorithm`` (the loop of the
constraint algorithm of Section 3) with ``records`` (its stages and result), ``analysis``
(:func:`analyze_constraints`, the Lagrangian entry point),
``integrability`` (Frobenius test of the constraint distribution),
``symmetries`` (Section 5), ``exceptional`` (the parameter values where a generic
decision's datum vanishes, their ``components``; the verdicts built on them are in
:mod:`nhham.verdict`).
"""

from nhham.lazy import by_module, lazy_exports

_LAZY = by_module({
    "geometry": ("lagrangian_geometry", "LagrangianGeometry", "DynamicsIngredients"),
    "submanifold": ("Submanifold",),
    "decision": ("Decision", "Assumption"),
    "engine": ("Policy", "decide"),
    "analysis": ("analyze_constraints", "ConstraintAnalysis"),
    "algorithm": ("run_algorithm",),
    "integrability": ("integrability",),
    "exceptional": ("exceptional_conditions",),
    "symmetries": ("constant_of_motion", "cyclic_constants", "lie_symmetry", "complete_lift"),
})
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
