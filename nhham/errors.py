"""Exception hierarchy of nhham.

Every error the library raises on purpose derives from :class:`NhhamError`.
:class:`InputError` and its subclasses mean "the user's input is wrong" (the
command exits with status 2); :class:`ComputationError` and its subclasses mean
"a computation could not be carried out" and :class:`BudgetExceeded` "the time
bound ran out" (status 3: the message says why and what to do); an exception
nhham did not raise on purpose is an internal failure (status 1).
:class:`UsageError` is the command line's share of bad input.

Every error may carry the key path or option it is about (``constraints[1]``,
``parameters.m``, ``--atol``) as :attr:`NhhamError.key`; the command's JSON
envelope reports it as ``error.key``. Collected problems (``problems``) are each
``"<key>: <what is wrong>"`` and the first one's key is the error's.
"""

from __future__ import annotations

import re

__all__ = [
    "NhhamError",
    "InputError",
    "UsageError",
    "ParseError",
    "SceneError",
    "ValidationError",
    "SingularLagrangianError",
    "NonAffineConstraintError",
    "RedundantConstraintError",
    "MissingParameterValueError",
    "InconsistentInitialDataError",
    "ComputationError",
    "BudgetExceeded",
    "ClosedFormTooLarge",
    "EmptySubmanifoldError",
    "NhhamWarning",
    "OptionalDependencyError",
    "OutputUnwritable",
    "key_of",
]

# The key path a problem starts with: ``constraints[1]: ...``, ``parameters.m: ...``,
# ``holonomic[0] (time derivative): ...``, ``--atol: ...``.
_LEADING_KEY = re.compile(r"^(--[a-z][a-z-]*|[^\W\d][\w-]*(?:\[\d+\]|\.[\w\"-]+)*)"
                          r"(?: \([^)]*\))?: ")


def key_of(problem: str) -> str | None:
    """The key path a one-line problem starts with, or None.

    >>> key_of("constraints[1]: unknown name 'R'")
    'constraints[1]'
    >>> key_of("holonomic[0] (time derivative): 0.5 at the initial state")
    'holonomic[0]'
    >>> key_of("the constraints are inconsistent") is None
    True
    """
    match = _LEADING_KEY.match(str(problem))
    return match.group(1) if match else None


class NhhamError(Exception):
    """Root of every exception nhham raises on purpose.

    Parameters
    ----------
    message : str
    key : str, optional
        The key path or option the error is about, when one is known.

    Examples
    --------
    >>> import nhham
    >>> try:
    ...     nhham.parse_expression("x + y", ["x"], where="constraints[1]")
    ... except nhham.NhhamError as exc:
    ...     print(type(exc).__name__, exc.key)
    ParseError constraints[1]
    """

    def __init__(self, message: str = "", *, key: str | None = None):
        super().__init__(message)
        self.key = key


class InputError(NhhamError):
    """The user's input (system description, scene, options) is invalid.

    ``problems``: every problem found, when a check collected several before raising
    once (empty otherwise).

    Examples
    --------
    >>> from nhham import time_budget
    >>> with time_budget(-1):
    ...     pass
    Traceback (most recent call last):
        ...
    nhham.errors.InputError: time_budget: seconds must be a positive finite number, got -1
    """

    problems: tuple[str, ...] = ()


class UsageError(InputError):
    """The command line is invalid: an unknown option, a value out of its range."""


class ParseError(InputError):
    """An expression could not be parsed against the symbol table.

    Examples
    --------
    >>> from nhham import parse_expression
    >>> parse_expression("x + y", ["x"], where="constraints[1]")
    Traceback (most recent call last):
        ...
    nhham.errors.ParseError: constraints[1]: unknown name 'y'
    """


class SceneError(InputError):
    """A scene file is malformed: syntax, unknown keys, wrong types.

    Examples
    --------
    >>> from nhham import loads_scene
    >>> loads_scene('coordinates = ["x"]\\nlagrangian = "x_dot**2/2"\\nmass = 1')
    Traceback (most recent call last):
        ...
    nhham.errors.SceneError: <string>: mass: unknown key (known keys: name, ...)
    """


class ValidationError(InputError):
    """One or more problems found while validating a system description.

    Parameters
    ----------
    problems : sequence of str
        Every problem found, each naming the offending key or expression.
        Validation collects all problems before raising once.

    Examples
    --------
    >>> from nhham import System
    >>> System(["x"], "x_dot**2/2 + q")
    Traceback (most recent call last):
        ...
    nhham.errors.ValidationError: lagrangian: unknown name 'q'
    """

    def __init__(self, problems, *, key: str | None = None):
        self.problems = tuple(problems)
        if len(self.problems) == 1:
            message = self.problems[0]
        else:
            message = f"{len(self.problems)} problems: " + "; ".join(self.problems)
        first = key_of(self.problems[0]) if self.problems else None
        super().__init__(message, key=key if key is not None else first)


class SingularLagrangianError(ValidationError):
    """The Hessian W = d2L/dv dv is singular where W^-1 is needed.

    A singular Lagrangian is a valid system (the Dirac-Bergmann chain of ``classify``
    answers it); the routes that need W^-1 refuse it with this error.

    Examples
    --------
    >>> from nhham import System, lagrangian_geometry
    >>> lagrangian_geometry(System(["x", "y"], "x_dot**2/2"))
    Traceback (most recent call last):
        ...
    nhham.errors.SingularLagrangianError: lagrangian: the Hessian W = d2L/dv dv is singular (rank 1 of 2; null direction [0, 1]); ...
    """


class NonAffineConstraintError(ValidationError):
    """A velocity constraint not affine in the velocities that Chetaev's rule cannot take:
    its d phi/d v vanishes on all of M_1, so it would have no reaction (``DESIGN.md`` §2).

    Examples
    --------
    >>> from nhham import System
    >>> System(["x", "y"], "(x_dot**2 + y_dot**2)/2", ["(x_dot - y_dot)**2"])
    Traceback (most recent call last):
        ...
    nhham.errors.NonAffineConstraintError: constraints[0]: d phi/d v = (2*x_dot - 2*y_dot, -2*x_dot + 2*y_dot) vanishes on M_1 ...
    """


class RedundantConstraintError(ValidationError):
    """The constraint one-forms mu_i are linearly dependent.

    A problem that dropping the constraint would solve ends with :attr:`ADVICE`
    (the command says ``--drop-redundant`` instead).

    Examples
    --------
    >>> from nhham import System
    >>> System(["x", "y"], "(x_dot**2 + y_dot**2)/2", ["x_dot - y_dot", "2*x_dot - 2*y_dot"])
    Traceback (most recent call last):
        ...
    nhham.errors.RedundantConstraintError: constraints[1]: 2*x_dot - 2*y_dot is redundant, a combination of the others: constraints[1] = (2)*constraints[0] (pass drop_redundant=True to drop it)
    """

    #: How the Python API drops a redundant velocity constraint.
    ADVICE = "pass drop_redundant=True to drop it"


class MissingParameterValueError(InputError):
    """A numeric value is needed for a parameter that has none.

    Examples
    --------
    >>> from nhham import System, numeric_model
    >>> spring = System(["x"], "m*x_dot**2/2 - k*x**2/2", parameters={"m": 1.0, "k": None})
    >>> numeric_model(spring, backend="numpy")
    Traceback (most recent call last):
        ...
    nhham.errors.MissingParameterValueError: parameters: no numeric value for k (needed for numbers)
    """


class InconsistentInitialDataError(InputError):
    """Initial data do not satisfy the constraints.

    Examples
    --------
    The Cartesian pendulum (l = 1) at y = -0.5: g = x**2 + y**2 - l**2 = -0.75.

    >>> from nhham import models, numeric_model
    >>> from nhham.numerics.linearization import linearize
    >>> model = numeric_model(models.pendulum_cartesian(), backend="numpy")
    >>> linearize(model, dict(x=0.0, y=-0.5, x_dot=0.0, y_dot=0.0))
    Traceback (most recent call last):
        ...
    nhham.errors.InconsistentInitialDataError: steady: the state is not on M_1: holonomic[0] (position) = -0.75
    """


class OptionalDependencyError(InputError, ImportError):
    """The requested output needs an optional extra that is not installed.

    Examples
    --------
    ``except ImportError`` catches it too:

    >>> from nhham import InputError, OptionalDependencyError
    >>> issubclass(OptionalDependencyError, ImportError), issubclass(OptionalDependencyError, InputError)
    (True, True)
    """


class ComputationError(NhhamError):
    """A computation could not be carried out (not the user's fault).

    The command exits 3 with the message, which says why and what to do (error kind
    ``computation``).

    Examples
    --------
    >>> from nhham import classify_constraints, dirac_bracket, models
    >>> sampled = classify_constraints(models.pendulum_cartesian(), method="sampled")
    >>> dirac_bracket(sampled)
    Traceback (most recent call last):
        ...
    nhham.errors.ComputationError: the Dirac bracket needs the constraints in (q, p): classify with method='exact' (this classification: 'sampled')
    """


class BudgetExceeded(NhhamError):
    """A time budget (``nhham.time_budget``, the command's ``--budget``) ran out.

    Examples
    --------
    >>> import time
    >>> from nhham import BudgetExceeded, time_budget
    >>> with time_budget(0.05):
    ...     time.sleep(2)
    Traceback (most recent call last):
        ...
    nhham.errors.BudgetExceeded: the budget of 0.05 s ran out

    Attributes
    ----------
    part : str
        The parts of the work open where it ran out (:func:`nhham.progress.current`,
        set as it leaves the innermost one; "" outside every part).
    """

    part: str = ""


class ClosedFormTooLarge(ComputationError):
    """A closed form (a symbolic solve with C) refused by the size guard; the message
    names the implicit form to use instead and how to ask for the closed form anyway."""


class NhhamWarning(UserWarning):
    """A result or a request that deserves the user's attention (not an error).

    Examples
    --------
    >>> import warnings
    >>> from nhham import NhhamWarning
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("error", NhhamWarning)   # every such warning an error
    ...     warnings.warn("a doubtful decision", NhhamWarning)
    Traceback (most recent call last):
        ...
    nhham.errors.NhhamWarning: a doubtful decision
    """


class EmptySubmanifoldError(InputError, ComputationError):
    """No point of a constraint submanifold M_k was found: it is most likely empty.

    Reported as bad input (the command exits 2: the usual cause is a holonomic
    constraint without a real solution), and still a :class:`ComputationError` for
    the constraint algorithm, which records an empty M_k as an inconsistency.
    """


class OutputUnwritable(ComputationError):
    """A result could not be written (a full disk, a quota, a folder made read-only while
    the command ran): the command ran, and exits 3 saying what it kept and what to do."""
