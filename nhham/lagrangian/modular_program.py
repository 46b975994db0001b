"""A :class:`~nhham.lagrangian.domains.Program` run modulo p on plain integers.

The modular points of the exact decisions (:class:`~nhham.lagrangian.linalg.ModularBackend`)
run the same straight-line program at every point. Through :class:`~.domains.ModP` each
product or sum allocates an object and dispatches on its operand's type: half a million
of them for the bicycle's checks. Here the residues are Python integers, reduced once per
operation; only the operations that may meet an angle (an :class:`~.domains.Angle`,
whose sums and integer multiples stay angles) run the generic arithmetic, and sin, cos,
tan, cot of an angle are read off its circle point as there. The values are those of
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

from nhham.lagrangian.domains import PRIME, Angle, ModP, NotExact

__all__ = ["ModularProgram"]


class ModularProgram:
    """``program`` run on residues modulo p (see the module docstring).

    Parameters
    ----------
    program : nhham.lagrangian.domains.Program
    """

    def __init__(self, program) -> None:
        self.program = program
        self._plans: dict = {}

    def _plan(self, angles: frozenset) -> list:
        """Per operation whether its value may be an Angle (its symbol is one, or it is
        a sum or product with such an operand): those run the generic arithmetic."""
        plan: list = []
        for kind, data, args in self.program.ops:
            if kind == "symbol":
                plan.append(data in angles)
            elif kind in ("add", "mul"):
                plan.append(any(plan[a] for a in args))
            else:
                plan.append(False)
        return plan

    def run(self, env: dict) -> list:
        """The residues (ints in [0, p)) of the program's outputs at ``env`` (Symbol ->
        ModP, int, rational or Angle)."""
        angles = frozenset(s for s, v in env.items() if isinstance(v, Angle))
        plan = self._plans.get(angles)
        if plan is None:
            plan = self._plans[angles] = self._plan(angles)
        ops = self.program.ops
        values: list = []
        push = values.append
        for i, (kind, data, args) in enumerate(ops):
            if plan[i]:
                push(_generic(kind, data, [_object(ops, values, a) for a in args], env))
            elif kind == "mul":
                out = 1
                for a in args:
                    out = out * _residue(values[a]) % PRIME
                push(out)
            elif kind == "add":
                push(sum(_residue(values[a]) for a in args) % PRIME)
            elif kind == "symbol":
                if data not in env:
                    raise NotExact(f"no exact value for {data}")
                push(ModP.lift(env[data]).v)
            elif kind == "constant":
                push(ModP.lift(data).v)
            elif kind == "function":
                a = args[0]
                arg = values[a] if isinstance(values[a], Angle) else _object(ops, values, a)
                push(ModP.lift(data(arg)).v)
            elif kind == "root":
                if ops[args[0]][0] == "constant":   # as square_root of a rational
                    raise NotExact("sqrt has no exact value at a rational point")
                root = pow(_residue(values[args[0]]), (PRIME + 1) // 4, PRIME)
                if root * root % PRIME != _residue(values[args[0]]):
                    raise ZeroDivisionError("not a square modulo p")
                push(_power(root, data[1]))
            else:
                push(_power(_residue(values[args[0]]), data))
        return [_residue(values[i]) for i in self.program.outputs]


def _residue(value) -> int:
    """An operation's value as a residue (an Angle's polynomial value)."""
    if isinstance(value, Angle):
        return ModP.lift(value.value).v
    return value


def _object(ops, values, a):
    """Operand ``a`` as the generic arithmetic takes it: a constant as written (an integer
    multiple of an angle needs the integer), a residue as a ModP, an Angle as it is."""
    value = values[a]
    if isinstance(value, Angle):
        return value
    kind, data, _ = ops[a]
    return data if kind == "constant" else ModP(value)


def _generic(kind, data, operands, env):
    """A sum, product or symbol that may be an Angle, as ``Program.run`` computes it."""
    if kind == "symbol":
        if data not in env:
            raise NotExact(f"no exact value for {data}")
        out = env[data]
    else:
        out = 0 if kind == "add" else 1
        for x in operands:
            out = out + x if kind == "add" else out * x
    return out if isinstance(out, Angle) else ModP.lift(out).v


def _power(base: int, k: int) -> int:
    if k >= 0:
        return pow(base, k, PRIME)
    if base == 0:
        raise ZeroDivisionError("division by zero modulo p")
    return pow(pow(base, -k, PRIME), -1, PRIME)
