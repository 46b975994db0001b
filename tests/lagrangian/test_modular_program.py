"""ModularProgram against Program.run with ModP values: the same residues and the same
exceptions, on hand-made expressions and on the bicycle's W, forcing and constraint rows
at random modular points."""

import random

import pytest
import sympy as sp
from sympy.external.gmpy import MPQ

from nhham.lagrangian.domains import PRIME, Angle, ModP, NotExact, Program
from nhham.lagrangian.modular_program import ModularProgram

x, y, q, r = sp.symbols("x y q r")


def _angle(rng, value=True):
    t = ModP(rng.randrange(1, PRIME))
    one = 1 + t * t
    return Angle(ModP(rng.randrange(PRIME)) if value else None, (1 - t * t) / one,
                 2 * t / one)


def _reference(exprs, env):
    """Program.run's values as residues, or the exception's type."""
    try:
        return [ModP.lift(v).v for v in Program(exprs).run(env)]
    except (NotExact, ZeroDivisionError) as exc:
        return type(exc)


def _modular(exprs, env):
    try:
        return ModularProgram(Program(exprs)).run(env)
    except (NotExact, ZeroDivisionError) as exc:
        return type(exc)


EXPRESSIONS = [
    [x * y + 3 * x ** 2 / 7 - sp.Rational(5, 3)],
    [sp.sin(q + r) * x - sp.cos(2 * q - r) * y ** -2],
    [sp.tan(q) + sp.cot(r - q) * x, sp.cos(-q)],
    [sp.sqrt(x ** 2 + y ** 2) ** 3, x / (y - y)],    # a square or not; 1/0
    [q + r, q * x, 2 * q, q ** 2],                    # angle values used as numbers
    [sp.sin(x)],                                      # sin of a non-angle: NotExact
    [sp.sqrt(2) * x],                                 # sqrt of a rational: NotExact
    [sp.cos(3 * q + x * 0) + sp.sin(q - r - q)],
    [(x + q) ** -3, sp.Rational(1, 2 ** 61 - 1) * x],  # denominator divisible by p
    [sp.sqrt(y) * x, y ** 2 * x / (y + 1), y * y],    # y may be an exact rational
    [sp.sin(y) + x, sp.cos(y * r)],                   # sin of an exact 0 is 0
]


@pytest.mark.parametrize("exprs", EXPRESSIONS, ids=range(len(EXPRESSIONS)))
def test_same_residues_and_exceptions_as_program_run(exprs):
    rng = random.Random(7)
    for i in range(30):
        # y a residue, or (as a parameter fixed at the scene's value) an exact rational
        exact_y = [MPQ(3, 2), 0, 4, MPQ(-1, 7)][i % 4] if i % 3 else None
        env = {x: ModP(rng.randrange(PRIME)),
               y: ModP(rng.randrange(1, 4)) if exact_y is None else exact_y,
               q: _angle(rng), r: _angle(rng, value=rng.random() < 0.7)}
        assert _modular(exprs, env) == _reference(exprs, env)


def test_bicycle_rows_at_modular_points():
    from nhham.lagrangian.geometry import lagrangian_geometry
    from nhham.system.scene import load_scene

    system = load_scene("examples/whipple_bicycle.toml").system
    G = lagrangian_geometry(system)
    exprs = list(G.hessian) + list(G.forcing) + list(system.mu) + list(G.drift)
    angles = set().union(*(f.args[0].free_symbols for e in exprs
                           for f in sp.sympify(e).atoms(sp.sin, sp.cos)))
    rng = random.Random(11)
    program = ModularProgram(Program(exprs))
    free = set().union(*(sp.sympify(e).free_symbols for e in exprs))
    compared = 0
    while compared < 3:   # points where a root exists (half of them), as the sampler draws
        env = {s: _angle(rng) if s in angles else ModP(rng.randrange(PRIME)) for s in free}
        want = _reference(exprs, env)
        try:
            got = program.run(env)
        except ZeroDivisionError:
            assert want is ZeroDivisionError
            continue
        assert got == want
        assert sum(map(bool, got)) > len(exprs) // 2   # not a comparison of zeros
        compared += 1


def test_values_by_hand():
    """x = 3, q = 0 (cos q = 1, sin q = 0), y = 2: x^2/2 + cos(2q) = 11/2, sin(q + y) needs
    sin y (not an angle: NotExact), sqrt(y^2 x^2) = 6 or -6 (the root that is a square),
    (x - 3)^-1 has no inverse."""
    env = {x: ModP(3), y: ModP(2), q: Angle(ModP(0), ModP(1), ModP(0))}
    assert ModularProgram(Program([x ** 2 / 2 + sp.cos(2 * q)])).run(env) == [
        11 * pow(2, -1, PRIME) % PRIME]
    with pytest.raises(NotExact):
        ModularProgram(Program([sp.sin(q + y)])).run(env)
    root, = ModularProgram(Program([sp.sqrt(y ** 2 * x ** 2)])).run(env)
    assert root in (6, PRIME - 6)
    with pytest.raises(ZeroDivisionError):
        ModularProgram(Program([1 / (x - 3)])).run(env)
