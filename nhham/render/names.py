"""The names an expression in an output may use, and reading such expressions back."""

from __future__ import annotations

__all__ = ["output_names", "expression_parser"]


def output_names(system) -> list:
    """Coordinates, velocities, momenta, parameters and the multipliers ``lambda_i`` of
    ``system``, each once: what :func:`nhham.parse_expression` needs to read an output's
    expressions back.

    Examples
    --------
    >>> from nhham import models
    >>> output_names(models.rolling_disk())[:5]
    ['x', 'y', 'theta', 'phi', 'x_dot']
    """
    from nhham.system.naming import (acceleration_symbol, gauge_parameter_symbol, momentum_symbol,
                                     multiplier_symbol, primary_multiplier_symbol)

    coords = [q.name for q in system.coordinates]
    vels = [v.name for v in system.velocities]
    momenta = [momentum_symbol(q).name for q in system.coordinates]
    params = [p.name for p in system.parameters]
    multipliers = [multiplier_symbol(i + 1).name for i in range(max(system.m, len(
        getattr(system, "constraints", ()))))]
    if not getattr(system, "regular_lagrangian", True):
        # the Dirac-Bergmann chain's u^a and the gauge parameters with their derivatives
        n = len(coords)
        multipliers += [primary_multiplier_symbol(a + 1).name for a in range(n)]
        multipliers += [f"{primary_multiplier_symbol(a + 1).name}_dot" for a in range(n)]
        multipliers += [acceleration_symbol(q).name for q in system.coordinates]
        multipliers += [gauge_parameter_symbol(a + 1, k).name for a in range(n)
                        for k in range(4)]
    return list(dict.fromkeys(coords + vels + momenta + params + multipliers))


def expression_parser(system):
    """``parse(text)``: an output's expression read back with ``system``'s names."""
    from nhham.system.expressions import parse_expression

    names = output_names(system)
    return lambda text: parse_expression(text, names)
