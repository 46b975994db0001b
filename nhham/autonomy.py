"""Time as one datum, and the one place that says what a time-dependent system cannot do.

A system depends on the time t when its Lagrangian, a constraint (affine or holonomic)
or a force does: t is then its last parameter (``System.time``, its index
``System.time_slot``), a parameter without a value for the exact geometry (a generic
instant: a verdict holds for all t but a proper algebraic subset, as for a parameter
without a value) and the slot the generated code's loops set
(``NumericModel.time_slot``, from the same index). Every refusal of time — by the
constraint algorithm (an input in a secondary constraint), the integrators, the
linearisation — takes its words from
:func:`nonautonomous`, and every refusal that raises goes through
:func:`require_autonomous`.

This module belongs to the base (no sympy, no layer imported), so that the numeric
layer reads it too.
"""

from __future__ import annotations

from collections.abc import Sequence

from nhham.errors import InputError

__all__ = ["TIME_NAME", "TIME_IN_FORCES", "TIME_IN_GEOMETRY", "time_slot", "nonautonomous",
           "require_autonomous"]

#: The name of the time in scenes, force expressions and control laws.
TIME_NAME = "t"

# where -> (message, key of the InputError or None for a message that is not raised)
_MESSAGES = {
    # the constraint algorithm (C singular) met a secondary constraint in an input
    "secondary": ("forces: the secondary constraint {label} = {expression} depends on "
                  "{names}; the constraint algorithm needs forces that do not depend on "
                  "inputs where C is singular (give the inputs as parameters with values)",
                  "forces"),
    # a fixed-step integrator or the mpmath reference
    "method": ("method: {method!r} does not take time-dependent {what}; choose an adaptive "
               "method such as DOP853", "method"),
    # a steady motion of a system whose forces depend on t
    "linearize": ("linearize: the forces depend on time t; a steady motion needs autonomous "
                  "forces (give the inputs constant values instead)", "forces"),
    # a steady motion of a system whose L or constraints depend on t
    "linearize_geometry": ("{key}: depends on time t; a steady motion (and its "
                           "linearisation) needs L and the constraints autonomous", None),
}

#: The ``what`` of the "method" refusal: where the time enters.
TIME_IN_FORCES = "forces (t in the forces)"
TIME_IN_GEOMETRY = ("L or constraints (t in L or the constraints: the method's steps are "
                    "made for an autonomous constrained field)")


def time_slot(parameters: Sequence, time) -> int | None:
    """The index of the time among ``parameters`` (its last one), or None when the system
    does not depend on time.

    Parameters
    ----------
    parameters : sequence
        The system's parameters (``System.parameters``).
    time : object or None
        The time (``System.time``), None for an autonomous system.

    Examples
    --------
    >>> time_slot(("m", "u", "t"), "t"), time_slot(("m",), None)
    (2, None)
    """
    if time is None:
        return None
    return len(parameters) - 1


def nonautonomous(where: str, **details) -> str:
    """The words of a refusal of time at ``where``, one of ``"secondary"``, ``"method"``, ``"linearize"``, ``"linearize_geometry"``.

    Parameters
    ----------
    where : str
    **details
        The fields of that message: ``label``, ``expression``,
        ``names`` (secondary), ``method`` and ``what`` (method; default
        :data:`TIME_IN_FORCES`), ``key`` (linearize_geometry).

    Examples
    --------
    >>> nonautonomous("method", method="rk4")
    "method: 'rk4' does not take time-dependent forces (t in the forces); choose an adaptive method such as DOP853"
    """
    if where == "method":
        details.setdefault("what", TIME_IN_FORCES)
    return _MESSAGES[where][0].format(**details)


def require_autonomous(where: str, depends: bool, **details) -> None:
    """Refuse what depends on time at ``where`` with the message of :func:`nonautonomous`.

    Parameters
    ----------
    where : str
        ``"secondary"``, ``"method"``, ``"linearize"`` or ``"linearize_geometry"``.
    depends : bool
        Whether what is asked depends on time (or, for ``"secondary"``, on an input).
    **details
        The fields of the message.

    Raises
    ------
    InputError
        When ``depends``; its key names the option or scene key to change (``forces``,
        ``method``, or the ``key`` given: ``lagrangian``, ``constraints[0]``).

    Examples
    --------
    >>> require_autonomous("linearize", False)
    >>> try:
    ...     require_autonomous("linearize", True)
    ... except InputError as error:
    ...     print(error.key)
    forces
    """
    if depends:
        key = _MESSAGES[where][1] or details.get("key")
        raise InputError(nonautonomous(where, **details), key=key)
