"""nhham: mechanical systems with non-holonomic constraints.

Public names are re-exported here explicitly. All but the system description
and the exceptions are imported on first use (PEP 562), so that a command
which only classifies never imports the numerical integrators.
"""

from importlib import import_module

from .errors import (
    ComputationError,
    InconsistentInitialDataError,
    InputError,
    MissingParameterValueError,
    NhhamError,
    NonAffineConstraintError,
    OptionalDependencyError,
    ParseError,
    RedundantConstraintError,
    SceneError,
    SingularLagrangianError,
    ValidationError,
)
from .system import DroppedConstraint, System

__version__ = "0.1.0"

# name -> module that defines it
_LAZY = {
    # Lagrangian side (paper Sections 2, 4, 5)
    "lagrangian_geometry": "lagrangian",
    "LagrangianGeometry": "lagrangian",
    "DynamicsIngredients": "lagrangian",
    "Submanifold": "onmanifold",
    "Decision": "onmanifold",
    "constant_of_motion": "symmetries",
    "cyclic_constants": "symmetries",
    "lie_symmetry": "symmetries",
    "complete_lift": "symmetries",
    # constraint algorithm (Section 3)
    "analyze_constraints": "algorithm",
    "ConstraintAnalysis": "algorithm",
    "run_algorithm": "algorithm",
    "integrability": "integrability",
    # Hamiltonian side (Section 6)
    "legendre_map": "legendre",
    "LegendreMap": "legendre",
    "canonical_bracket": "brackets",
    "BracketAlgebra": "brackets",
    "hamiltonian_side": "hamiltonian",
    "HamiltonianSide": "hamiltonian",
    "nonholonomic_bracket": "hamiltonian",
    "classify_constraints": "classification",
    "ConstraintClasses": "classification",
    "dirac_bracket": "classification",
    "dirac_vs_projected": "classification",
    "cross_check": "crosscheck",
    "CrossCheckReport": "crosscheck",
    # numbers
    "numeric_model": "codegen",
    "NumericModel": "numeric",
    "simulate": "integrate",
    "SimulationResult": "integrate",
    "work_precision": "workprecision",
    # input and output
    "load_scene": "scene",
    "loads_scene": "scene",
    "dump_scene": "scene",
    "Scene": "scene",
    "parse_expression": "expressions",
    "from_mechanics": "mechanics",
    "from_lagranges_method": "mechanics",
    "models": None,
}

__all__ = [
    "System",
    "DroppedConstraint",
    "NhhamError",
    "InputError",
    "ParseError",
    "SceneError",
    "ValidationError",
    "SingularLagrangianError",
    "NonAffineConstraintError",
    "RedundantConstraintError",
    "MissingParameterValueError",
    "InconsistentInitialDataError",
    "OptionalDependencyError",
    "ComputationError",
    *_LAZY,
]


def __getattr__(name):
    if name not in _LAZY:
        raise AttributeError(f"module 'nhham' has no attribute {name!r}")
    module = _LAZY[name]
    value = import_module(f".{name}" if module is None else f".{module}", __name__)
    if module is not None:
        value = getattr(value, name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
