"""Naming conventions for generated symbols (one home for each).

A coordinate ``x`` has velocity ``x_dot``, acceleration ``x_ddot`` and
momentum ``p_x``; the i-th Lagrange multiplier is ``lambda_i`` (1-based); time is ``t``.
"""

from __future__ import annotations

import sympy as sp

from nhham.autonomy import TIME_NAME

__all__ = [
    "velocity_symbol",
    "acceleration_symbol",
    "momentum_symbol",
    "multiplier_symbol",
    "as_symbol",
    "TIME",
]

#: The time t, the only name a force, a dissipation function or a control law may use for
#: time (``System.forces``); L and the constraints are autonomous.
TIME = sp.Symbol(TIME_NAME)


def as_symbol(name_or_symbol) -> sp.Symbol:
    """Return a plain :class:`sympy.Symbol` for a name or a symbol."""
    if isinstance(name_or_symbol, sp.Symbol):
        return sp.Symbol(name_or_symbol.name)
    if isinstance(name_or_symbol, str):
        return sp.Symbol(name_or_symbol)
    raise TypeError(f"expected a name or a sympy Symbol, got {name_or_symbol!r}")


def velocity_symbol(q: sp.Symbol) -> sp.Symbol:
    """Velocity symbol ``<q>_dot`` of coordinate ``q``."""
    return sp.Symbol(f"{q.name}_dot")


def acceleration_symbol(q: sp.Symbol) -> sp.Symbol:
    """Acceleration symbol ``<q>_ddot`` of coordinate ``q``."""
    return sp.Symbol(f"{q.name}_ddot")


def momentum_symbol(q: sp.Symbol) -> sp.Symbol:
    """Momentum symbol ``p_<q>`` of coordinate ``q``."""
    return sp.Symbol(f"p_{q.name}")


def multiplier_symbol(i: int) -> sp.Symbol:
    """The i-th Lagrange multiplier ``lambda_<i>`` (1-based)."""
    return sp.Symbol(f"lambda_{i}")


def primary_multiplier_symbol(a: int) -> sp.Symbol:
    """The multiplier ``u_<a>`` of the a-th primary constraint of a singular Lagrangian
    (1-based): H_T = H_c + u^a phi_a."""
    return sp.Symbol(f"u_{a}")


def gauge_parameter_symbol(a: int, k: int = 0) -> sp.Symbol:
    """The k-th time derivative of the a-th gauge parameter: ``eps_<a>``, ``eps_<a>_dot``,
    ``eps_<a>_ddot``, then ``eps_<a>_d<k>ot``."""
    return sp.Symbol(f"eps_{a}" + {0: "", 1: "_dot", 2: "_ddot"}.get(k, f"_d{k}ot"))
