"""A :class:`~nhham.lagrangian.domains.Program` run modulo p on plain integers.

The modular points of the exact decisions (:class:`~nhham.lagrangian.linalg.ModularBackend`)
run the same straight-line program at every point. Through :class:`~.domains.ModP` each
product or sum allocates an object and dispatches on its operand's type: half a million
of them for the bicycle's checks. Here the residues are Python integers, reduced once per
operation; an operation that meets anything else (an :class:`~.domains.Angle`, whose sums
and integer multiples stay angles, an exact rational not yet reduced, a function) runs
the generic arithmetic on the objects Program.run would hold. The values are those of
``Program.run`` with ModP values: the same residues, the same exceptions
(ZeroDivisionError where an inverse or a square root does not exist, NotExact where a
function meets a value that is not an angle).

Examples
--------
>>> import sympy as sp
>>> from nhham.lagrangian.domains import Angle, ModP, Program
>>> from nhham.lagrangian.modular_program import ModularProgram
>>> x, q = sp.symbols("x q")
>>> env = {x: ModP(3), q: Angle(ModP(0), ModP(1), ModP(0))}
>>> ModularProgram(Program([x**2 / 2 + sp.cos(2 * q), sp.sin(q + x * 0)])).run(env)
[1152921504606846981, 0]
>>> [ModP.lift(v).v for v in Program([x**2 / 2 + sp.cos(2 * q)]).run(env)]
[1152921504606846981]
"""

from __future__ import annotations

from nhham.lagrangian.domains import PRIME, Angle, ModP, NotExact, Program

__all__ = ["ModularProgram"]


class ModularProgram:
    """``program`` run on residues modulo p (see the module docstring).

    Parameters
    ----------
    program : nhham.lagrangian.domains.Program
    """

    def __init__(self, program) -> None:
        self.program = program

    def run(self, env: dict) -> list:
        """The residues (ints in [0, p)) of the program's outputs at ``env`` (Symbol ->
        ModP, int, rational or Angle)."""
        values: list = []   # a residue (int), or an _Exact or Angle: see _object
        push = values.append
        for kind, data, args in self.program.ops:
            if kind == "mul" and all(type(values[a]) is int for a in args):
                out = 1
                for a in args:
                    out = out * values[a] % PRIME
                push(out)
            elif kind == "add" and all(type(values[a]) is int for a in args):
                push(sum(values[a] for a in args) % PRIME)
            elif kind == "symbol":
                if data not in env:
                    raise NotExact(f"no exact value for {data}")
                push(_stored(env[data]))
            elif kind == "constant":
                push(_Exact(data))
            elif kind == "power" and type(values[args[0]]) is int:
                push(_power(values[args[0]], data))
            else:   # an angle, an exact rational, a function, a root: Program.run's own
                push(_stored(Program.apply(kind, data, [_object(values[a]) for a in args],
                                            env)))
        return [values[i] if type(values[i]) is int else _residue(_object(values[i]))
                for i in self.program.outputs]


class _Exact:
    """A value Program.run keeps as an exact rational (a constant, a parameter fixed at a
    rational value, or arithmetic among them): sqrt and sin/cos treat those differently
    from residues, so it is not reduced until it meets one."""

    __slots__ = ("value",)

    def __init__(self, value) -> None:
        self.value = value


def _stored(value):
    """A value as stored: a ModP as its residue, anything else wrapped or as it is."""
    if isinstance(value, ModP):
        return value.v
    return value if isinstance(value, Angle) else _Exact(value)


def _object(value):
    """A stored value as Program.run holds it."""
    if type(value) is int:
        return ModP(value)
    return value.value if isinstance(value, _Exact) else value


def _residue(value) -> int:
    """An output as a residue: an Angle by its value (NotExact without one)."""
    return ModP.lift(value.value if isinstance(value, Angle) else value).v


def _power(base: int, k: int) -> int:
    if k >= 0:
        return pow(base, k, PRIME)
    if base == 0:
        raise ZeroDivisionError("division by zero modulo p")
    return pow(pow(base, -k, PRIME), -1, PRIME)
