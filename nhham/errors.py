"""Exception hierarchy of nhham.

Every error the library raises on purpose derives from :class:`NhhamError`.
:class:`InputError` and its subclasses mean "the user's input is wrong" (the
command exits with status 2); anything else rooted at :class:`NhhamError` is a
failure to compute (status 1).
"""

from __future__ import annotations

__all__ = [
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
    "OptionalDependencyError",
]


class NhhamError(Exception):
    """Root of every exception nhham raises on purpose."""


class InputError(NhhamError):
    """The user's input (system description, scene, options) is invalid."""


class ParseError(InputError):
    """An expression could not be parsed against the symbol table."""


class SceneError(InputError):
    """A scene file is malformed: syntax, unknown keys, wrong types."""


class ValidationError(InputError):
    """One or more problems found while validating a system description.

    Parameters
    ----------
    problems : sequence of str
        Every problem found, each naming the offending key or expression.
        Validation collects all problems before raising once.
    """

    def __init__(self, problems):
        self.problems = tuple(problems)
        if len(self.problems) == 1:
            message = self.problems[0]
        else:
            message = f"{len(self.problems)} problems: " + "; ".join(self.problems)
        super().__init__(message)


class SingularLagrangianError(ValidationError):
    """The Hessian W = d2L/dv dv is singular (outside the paper's scope)."""


class NonAffineConstraintError(ValidationError):
    """A velocity constraint is not affine in the velocities."""


class RedundantConstraintError(ValidationError):
    """The constraint one-forms mu_i are linearly dependent."""


class MissingParameterValueError(InputError):
    """A numeric value is needed for a parameter that has none."""


class InconsistentInitialDataError(InputError):
    """Initial data do not satisfy the constraints."""


class OptionalDependencyError(InputError, ImportError):
    """The requested output needs an optional extra that is not installed."""


class ComputationError(NhhamError):
    """A computation could not be carried out (not the user's fault)."""
