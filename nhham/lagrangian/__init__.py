"""The paper on TQ (Sections 2-5): the exact geometry layer.

Modules: ``domains``, ``linalg`` and ``formulas`` (the arithmetics, their linear
algebra, and the paper's formulas at a point written once for all of them),
``points`` (exact points of M_1), ``submanifold`` (deciding ranks and vanishing on M_k,
with a :class:`Decision` (``decision``) recording how; ``sampled`` at float points),
``geometry`` (E_L, omega_L, xi_L, Z_i, C, P(xi_L)), ``algorithm`` (the loop of the
constraint algorithm of Section 3) with ``records`` (its stages and result), ``analysis``
(:func:`analyze_constraints`, the Lagrangian entry point),
``integrability`` (Frobenius test of the constraint distribution),
``symmetries`` (Section 5), ``exceptional`` (the parameter values where a generic
decision's datum vanishes; the verdicts built on them are in :mod:`nhham.verdict`).
"""

from nhham.lazy import lazy_exports

_LAZY = {
    "lagrangian_geometry": "geometry",
    "LagrangianGeometry": "geometry",
    "DynamicsIngredients": "geometry",
    "Submanifold": "submanifold",
    "Decision": "decision",
    "analyze_constraints": "analysis",
    "ConstraintAnalysis": "analysis",
    "run_algorithm": "algorithm",
    "integrability": "integrability",
    "exceptional_conditions": "exceptional",
    "constant_of_motion": "symmetries",
    "cyclic_constants": "symmetries",
    "lie_symmetry": "symmetries",
    "complete_lift": "symmetries",
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
