"""nhham: mechanical systems with non-holonomic constraints."""

from .errors import (
    ComputationError,
    InconsistentInitialDataError,
    InputError,
    MissingParameterValueError,
    NhhamError,
    NonAffineConstraintError,
    ParseError,
    RedundantConstraintError,
    SceneError,
    SingularLagrangianError,
    ValidationError,
)
from .system import DroppedConstraint, System

__version__ = "0.1.0"

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
    "ComputationError",
]
