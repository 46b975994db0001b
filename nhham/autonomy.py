"""Time as one datum, and the one place that says what a time-dependent system cannot do.

A system depends on the time t when its forces do: t is then its last parameter
(``System.time``, its index ``System.time_slot``), a parameter without a value for the
exact geometry (any instant) and the slot the generated code's loops set
(``NumericModel.time_slot``, from the same index). L and the constraints are
autonomous. Every refusal of time — by the scene parser, the sympy.physics.mechanics
adapter, the screening of unknown names, the constraint algorithm, the integrators
and the linearisation — takes its words from :func:`nonautonomous`, and every refusal
that raises goes through :func:`require_autonomous`: time-dependent constraints will
change this module and the places that call it, nothing else.

This module belongs to the base (no sympy, no layer imported), so that the numeric
layer reads it too.
"""

from __future__ import annotations

from collections.abc import Sequence

from nhham.errors import InputError

__all__ = ["TIME_NAME", "time_slot", "nonautonomous", "require_autonomous"]

#: The name of the time in scenes, force expressions and control laws.
TIME_NAME = "t"

# where -> (message, key of the InputError or None for a message that is not raised)
_MESSAGES = {
    # L or a constraint names t (the scene parser's hint to an unknown name)
    "scene": (" (systems are autonomous: L and the constraints may not depend on time t, "
              "a force may (forces = {{...}}); if t is a parameter, add it to parameters)",
              None),
    # the same, where expressions are screened before parsing
    "screening": ("; nhham's systems are autonomous: L and the constraints may not depend "
                  "on time t explicitly, a force may (forces=...; if t is a parameter, "
                  "declare it in parameters)", None),
    # a term of a sympy.physics.mechanics Lagrangian or constraint
    "mechanics": ("depends explicitly on time {t}; nhham handles autonomous systems only",
                  None),
    # the constraint algorithm (C singular) met a secondary constraint in t or an input
    "secondary": ("forces: the secondary constraint {label} = {expression} depends on "
                  "{names}; the constraint algorithm needs forces that do not depend on time "
                  "or inputs where C is singular (give the inputs as parameters with values)",
                  "forces"),
    # a fixed-step integrator or the mpmath reference
    "method": ("method: {method!r} does not take time-dependent forces (t in the forces); "
               "choose an adaptive method such as DOP853", "method"),
    # a steady motion
    "linearize": ("linearize: the forces depend on time t; a steady motion needs autonomous "
                  "forces (give the inputs constant values instead)", "forces"),
}


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
    """The words of a refusal of time at ``where``, one of ``"scene"``, ``"screening"``,
    ``"mechanics"``, ``"secondary"``, ``"method"``, ``"linearize"``.

    Parameters
    ----------
    where : str
    **details
        The fields of that message: ``t`` (mechanics), ``label``, ``expression``,
        ``names`` (secondary), ``method`` (method).

    Examples
    --------
    >>> nonautonomous("method", method="rk4")
    "method: 'rk4' does not take time-dependent forces (t in the forces); choose an adaptive method such as DOP853"
    """
    return _MESSAGES[where][0].format(**details)


def require_autonomous(where: str, depends: bool, **details) -> None:
    """Refuse what depends on time at ``where`` with the message of :func:`nonautonomous`.

    Parameters
    ----------
    where : str
        ``"secondary"``, ``"method"`` or ``"linearize"``.
    depends : bool
        Whether what is asked depends on time (or, for ``"secondary"``, on an input).
    **details
        The fields of the message.

    Raises
    ------
    InputError
        When ``depends``; its key names the option to change (``forces`` or ``method``).

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
        text, key = _MESSAGES[where]
        raise InputError(text.format(**details), key=key)
