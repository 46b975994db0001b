"""The arithmetics of exact decisions: the values a formula is evaluated in.

One interface, the Python operators (+, -, *, /, ** and ``sin``/``cos`` through
:func:`evaluate`), over several kinds of number:

* exact rationals (``MPQ``) and exact angles (:class:`Angle`: a rational value with a
  rational point of the unit circle);
* integers modulo the prime 2^61 - 1 (:class:`ModP`);
* the parameter field Q(p) and 200-bit floats, as sympy domain elements;
* float64 and mpmath (the numeric backends);
* :class:`Degree`: an upper bound on the degree of the numerator (and the factors of
  the denominator) of the same computation, for the Schwartz–Zippel bound.

A formula written once against these operators (:mod:`nhham.lagrangian.formulas`)
is evaluated in each by giving it values of that kind; matrices and their solves are
in :mod:`nhham.lagrangian.linalg`. A datum with no exact value (``exp``, ``sqrt`` except
modulo p, where :func:`square_root` fixes one branch) raises :class:`NotExact`.

Every evaluation can be repeated with :class:`Degree` objects in place of the
numbers: the same arithmetic then yields an upper bound on the degree of the
numerator of each quantity as a rational function of the drawn variables
(r, t, free velocities, free parameters). That is the "degree" of the
Schwartz–Zippel lemma: a nonzero rational function whose numerator has degree
at most D vanishes at a uniformly random point of S^N with probability at most
D/|S|. So "vanishes at k random exact points" is reported with the computed
error bound (D/(|S| − D_den))^k (points where a denominator vanishes are drawn
again, which the D_den term accounts for), and "nonzero at one exact point" is
a proof.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import sympy as sp
from sympy.external.gmpy import MPQ

from nhham.errors import NhhamError

__all__ = [
    "NotExact",
    "Angle",
    "ModP",
    "Degree",
    "PRIME",
    "SAMPLE_BITS",
    "RADICANDS",
    "evaluate",
    "Program",
    "square_root",
    "rank_bound",
    "minor_degree",
    "schwartz_zippel_bound",
    "ErrorBound",
]


# Sample set S = {1, ..., 2**SAMPLE_BITS}: large enough that a handful of points
# gives Schwartz–Zippel bounds far below 1e-30, small enough for quick rationals.
SAMPLE_BITS = 62

# The key of a degree environment under which :func:`evaluate` records the radicand of
# every sqrt it meets (radicand expression -> its Degree): each is a variable w of the
# lifted space with the equation w^2 = b.
RADICANDS = "radicands"


class NotExact(NhhamError):
    """The expression cannot be evaluated exactly at rational points."""


# ------------------------------------------------------------------ values
class Angle:
    """A coordinate's value at an exact point: polynomial value ``r`` and the point
    ``(c, s)`` of the unit circle standing for (cos q, sin q).

    Sums and integer multiples of angles stay angles (the circle points multiply
    as unit complex numbers); any other arithmetic uses ``r``. ``r``, ``c``, ``s``
    are exact rationals or :class:`Degree` bounds (the same code serves both).
    ``r = None``: the angle is known only by its circle point (a coordinate solved on
    a curved M, :mod:`nhham.lagrangian.curved`); using its value raises NotExact.
    """

    __slots__ = ("r", "c", "s")

    def __init__(self, r, c, s):
        self.r, self.c, self.s = r, c, s

    @classmethod
    def on_circle(cls, r, t) -> "Angle | None":
        """The angle of value ``r`` at the unit circle's rational point of parameter t,
        ((1 - t^2) / (1 + t^2), 2 t / (1 + t^2)); None where 1 + t^2 = 0 (over F_p)."""
        one = 1 + t * t
        if not one:
            return None
        return cls(r, (1 - t * t) / one, 2 * t / one)

    @property
    def value(self):
        """``r``; NotExact when the angle has only its circle point."""
        if self.r is None:
            raise NotExact("an angle solved on a curved M enters only through sin and cos")
        return self.r

    def _rotate(self, other):
        r = None if self.r is None or other.r is None else self.r + other.r
        return Angle(r, self.c * other.c - self.s * other.s,
                     self.s * other.c + self.c * other.s)

    def _times(self, k: int):
        out = Angle(0, 1, 0)
        base = self if k >= 0 else -self
        for _ in range(abs(k)):
            out = out._rotate(base)
        return out

    def __add__(self, other):
        if isinstance(other, Angle):
            return self._rotate(other)
        if isinstance(other, int) and other == 0:
            return self
        return self.value + other

    __radd__ = __add__

    def __neg__(self):
        return Angle(None if self.r is None else -self.r, self.c, -self.s)

    def __sub__(self, other):
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, other):
        if isinstance(other, int):
            return self._times(other)
        if isinstance(other, Angle):
            return self.value * other.value
        return self.value * other

    __rmul__ = __mul__

    def __truediv__(self, other):
        return self.value / (other.value if isinstance(other, Angle) else other)

    def __rtruediv__(self, other):
        return other / self.value

    def __pow__(self, k):
        return self.value ** k


# A Mersenne prime: reduction is cheap and 1/|F_p| is about 4e-19.
PRIME = 2 ** 61 - 1


class ModP:
    """An element of the field F_p (p = :data:`PRIME`).

    Used for proofs of full rank and of non-vanishing: a value computed from the
    expression tree modulo p (every inverse taken exists) that is nonzero shows
    that the rational value — hence the function — is nonzero. Mixed arithmetic
    with ints and exact rationals reduces them modulo p.
    """

    __slots__ = ("v",)

    def __init__(self, v: int):
        self.v = v % PRIME

    @staticmethod
    def lift(x) -> "ModP":
        if isinstance(x, ModP):
            return x
        if isinstance(x, int):
            return ModP(x)
        q = MPQ(x)
        den = int(q.denominator) % PRIME
        if den == 0:
            raise ZeroDivisionError("denominator divisible by p")
        return ModP(int(q.numerator) * pow(den, -1, PRIME))

    def __add__(self, other):
        if isinstance(other, (Angle, Degree)):
            return NotImplemented
        return ModP(self.v + ModP.lift(other).v)

    __radd__ = __add__

    def __sub__(self, other):
        if isinstance(other, (Angle, Degree)):
            return NotImplemented
        return ModP(self.v - ModP.lift(other).v)

    def __rsub__(self, other):
        return ModP(ModP.lift(other).v - self.v)

    def __neg__(self):
        return ModP(-self.v)

    def __mul__(self, other):
        if isinstance(other, (Angle, Degree)):
            return NotImplemented
        return ModP(self.v * ModP.lift(other).v)

    __rmul__ = __mul__

    def inverse(self) -> "ModP":
        if self.v == 0:
            raise ZeroDivisionError("division by zero modulo p")
        return ModP(pow(self.v, -1, PRIME))

    def __truediv__(self, other):
        if isinstance(other, (Angle, Degree)):
            return NotImplemented
        return self * ModP.lift(other).inverse()

    def __rtruediv__(self, other):
        return ModP.lift(other) * self.inverse()

    def __pow__(self, k: int):
        return ModP(pow(self.v, k, PRIME)) if k >= 0 else self.inverse() ** (-k)

    def __eq__(self, other):
        if isinstance(other, (ModP, int)):
            return self.v == ModP.lift(other).v
        return NotImplemented

    def __hash__(self):
        return hash(self.v)

    def __bool__(self):
        return self.v != 0

    def __repr__(self):
        return f"ModP({self.v})"


def square_root(x) -> "ModP | Degree":
    """The square root of ``x`` in F_p that is itself a square (p = 3 mod 4, so exactly
    one of the two roots is): one fixed branch of sqrt, the same at every occurrence,
    so that a point of a variety with w^2 = b keeps w = sqrt(b) throughout.

    Raises
    ------
    ZeroDivisionError
        ``x`` is not a square modulo p: the point is outside the domain of sqrt over
        F_p (the caller draws another).
    NotExact
        ``x`` is not a residue: sqrt leaves Q (a rational), and a degree bound of it is
        not kept.
    """
    if isinstance(x, Degree):
        # sqrt(b) is a variable w of the lifted space (w^2 = b among its equations,
        # counted in the variety's degree): degree 1, no denominator.
        return Degree(1)
    if not isinstance(x, ModP):
        raise NotExact("sqrt has no exact value at a rational point")
    root = ModP(pow(x.v, (PRIME + 1) // 4, PRIME))
    if root * root != x:
        raise ZeroDivisionError("not a square modulo p")
    return root


def _sin(x):
    if isinstance(x, Angle):
        return x.s
    if _is_zero_constant(x):
        return 0
    raise NotExact("sin of a number that is not an angle variable")


def _cos(x):
    if isinstance(x, Angle):
        return x.c
    if _is_zero_constant(x):
        return 1
    raise NotExact("cos of a number that is not an angle variable")


def _inverse(x):
    if isinstance(x, (Degree, ModP)):
        return x.inverse()
    return MPQ(1) / x  # ZeroDivisionError at a bad point: the caller draws again


def _is_zero_constant(x) -> bool:
    return isinstance(x, (int, MPQ)) and x == 0


_FUNCTIONS = {
    sp.sin: _sin,
    sp.cos: _cos,
    sp.tan: lambda x: _sin(x) / _cos(x),
    sp.cot: lambda x: _cos(x) / _sin(x),
}


def evaluate(exprs, env: dict, cache: dict | None = None) -> list:
    """Values of sympy expressions with symbols replaced by ``env`` values.

    Parameters
    ----------
    exprs : sequence of sympy.Expr
    env : dict
        Symbol -> value (exact rational, :class:`Angle`, or :class:`Degree`).
    cache : dict, optional
        Shared memo of subexpression values (for several calls at one point).

    Returns
    -------
    list
        One value per expression (``int``, ``MPQ``, ``Degree`` ...).

    Raises
    ------
    NotExact
        On a symbol missing from ``env``, a transcendental constant, a function
        other than sin/cos/tan/cot, or a non-integer power.
    """
    memo = {} if cache is None else cache
    values = [_value(sp.sympify(e), env, memo) for e in exprs]
    return [x.value if isinstance(x, Angle) else x for x in values]


def _value(e, env, memo):
    if e in memo:
        return memo[e]
    if e.is_Symbol:
        if e not in env:
            raise NotExact(f"no exact value for {e}")
        out = env[e]
    elif e.is_Integer:
        out = int(e)
    elif e.is_Rational:
        out = MPQ(int(e.p), int(e.q))
    elif e.is_Float:
        r = sp.Rational(str(e))
        out = MPQ(int(r.p), int(r.q))
    elif e.is_Add:
        out = 0
        for a in e.args:
            out = out + _value(a, env, memo)
    elif e.is_Mul:
        out = 1
        for a in e.args:
            out = out * _value(a, env, memo)
    elif e.is_Pow:
        base = _value(e.base, env, memo)
        if isinstance(base, Angle):
            base = base.value
        if e.exp.is_Rational and e.exp.q == 2:  # (sqrt b)^k, the root of F_p's choice
            if isinstance(base, Degree) and RADICANDS in env:
                env[RADICANDS][e.base] = base  # its w^2 = b counts in deg X
            base, k = square_root(base), int(e.exp.p)
        elif e.exp.is_Integer:
            k = int(e.exp)
        else:
            raise NotExact(f"non-integer power in {e}")
        out = base ** k if k >= 0 else _inverse(base ** (-k))
    elif e.func in _FUNCTIONS:
        out = _FUNCTIONS[e.func](_value(e.args[0], env, memo))
    else:
        raise NotExact(f"{e.func} cannot be evaluated exactly")
    memo[e] = out
    return out


class Program:
    """Expressions compiled once into a straight-line program over their DAG, then run
    at many points: the arithmetic of :func:`evaluate` without its walk of the tree
    (the hashing and dispatch of every node at every point, 2/3 of the cost on the
    bicycle's modular points).

    Parameters
    ----------
    exprs : sequence of sympy.Expr

    Raises
    ------
    NotExact
        At compilation: a transcendental constant, a function other than
        sin/cos/tan/cot, or a non-integer power other than a half-integer one.
    """

    def __init__(self, exprs):
        self.ops: list = []
        slots: dict = {}
        self.outputs = [self._compile(sp.sympify(e), slots) for e in exprs]

    def _compile(self, root, slots) -> int:
        stack = [(root, False)]
        while stack:
            e, ready = stack.pop()
            if e in slots:
                continue
            args = () if e.is_Atom else (e.base,) if e.is_Pow else e.args
            if not ready and args:
                stack.append((e, True))
                stack.extend((a, False) for a in args if a not in slots)
                continue
            slots[e] = len(self.ops)
            self.ops.append(self._op(e, [slots[a] for a in args]))
        return slots[root]

    @staticmethod
    def _op(e, args):
        if e.is_Symbol:
            return ("symbol", e, args)
        if e.is_Number:
            return ("constant", _value(e, {}, {}), args)
        if e.is_Add or e.is_Mul:
            return ("add" if e.is_Add else "mul", None, args)
        if e.is_Pow:
            if e.exp.is_Rational and e.exp.q == 2:
                return ("root", (e.base, int(e.exp.p)), args)
            if not e.exp.is_Integer:
                raise NotExact(f"non-integer power in {e}")
            return ("power", int(e.exp), args)
        if e.func in _FUNCTIONS:
            return ("function", _FUNCTIONS[e.func], args)
        raise NotExact(f"{e.func} cannot be evaluated exactly")

    @staticmethod
    def apply(kind: str, data, operands: list, env: dict):
        """One operation (``kind``, ``data`` of :attr:`ops`) on its operands' values: what
        :meth:`run` does at each step (sums and products inline there, for speed), and
        what :class:`~nhham.lagrangian.modular_program.ModularProgram` does where its
        residues meet an angle or an exact rational."""
        if kind in ("add", "mul"):
            out = 0 if kind == "add" else 1
            for x in operands:
                out = out + x if kind == "add" else out * x
            return out
        if kind == "function":
            return data(operands[0])
        base = operands[0]
        if isinstance(base, Angle):
            base = base.value
        if kind == "root":
            radicand, k = data
            if isinstance(base, Degree) and RADICANDS in env:
                env[RADICANDS][radicand] = base
            base = square_root(base)
        else:
            k = data
        return base ** k if k >= 0 else _inverse(base ** (-k))

    def run(self, env: dict) -> list:
        """The values at ``env`` (as :func:`evaluate` gives them)."""
        values: list = []
        push = values.append
        for kind, data, args in self.ops:
            if kind == "mul":
                out = 1
                for a in args:
                    out = out * values[a]
            elif kind == "add":
                out = 0
                for a in args:
                    out = out + values[a]
            elif kind == "symbol":
                if data not in env:
                    raise NotExact(f"no exact value for {data}")
                out = env[data]
            elif kind == "constant":
                out = data
            else:
                out = Program.apply(kind, data, [values[a] for a in args], env)
            push(out)
        return [values[i].value if isinstance(values[i], Angle) else values[i]
                for i in self.outputs]


# ----------------------------------------------------------------- degrees
class Degree:
    """Upper bound on a rational function N/D of the drawn variables.

    ``num`` bounds deg N; ``den`` maps each denominator factor (a key) to
    ``(degree, exponent)``. Circle factors (1 + t²) are shared keys, so sums of
    trigonometric terms keep one common denominator; every other denominator
    gets a fresh key. Arithmetic mirrors the exact evaluation.
    """

    __slots__ = ("num", "den")
    _fresh = itertools.count()

    def __init__(self, num: int = 0, den: dict | None = None):
        self.num, self.den = num, dict(den or {})

    @staticmethod
    def of(x) -> "Degree":
        if isinstance(x, Angle):
            x = x.r
        return x if isinstance(x, Degree) else Degree(0)

    @property
    def den_degree(self) -> int:
        return sum(d * k for d, k in self.den.values())

    def __add__(self, other):
        if _is_zero_constant(other):
            return self
        a, b = self, Degree.of(other)
        common = dict(a.den)
        for key, (d, k) in b.den.items():
            if key not in common or common[key][1] < k:
                common[key] = (d, k)
        total = sum(d * k for d, k in common.values())
        num = max(a.num + total - a.den_degree, b.num + total - b.den_degree)
        return Degree(num, common)

    __radd__ = __add__

    def __neg__(self):
        return self

    def __sub__(self, other):
        return self + other

    def __rsub__(self, other):
        return self + other

    def __mul__(self, other):
        if _is_zero_constant(other):
            return 0
        b = Degree.of(other)
        den = dict(self.den)
        for key, (d, k) in b.den.items():
            den[key] = (d, den[key][1] + k) if key in den else (d, k)
        return Degree(self.num + b.num, den)

    __rmul__ = __mul__

    def inverse(self) -> "Degree":
        if self.num == 0 and not self.den:
            return Degree(0)
        return Degree(self.den_degree, {("denominator", next(Degree._fresh)): (self.num, 1)})

    def __truediv__(self, other):
        return self * Degree.of(other).inverse()

    def __rtruediv__(self, other):
        return self.inverse() * other

    def __pow__(self, k: int):
        out = Degree(0)
        for _ in range(k):
            out = out * self
        return out

    def __repr__(self):
        return f"Degree(num={self.num}, den={self.den_degree})"


def rank_bound(rows) -> list[int]:
    """Per-row numerator degree contributions of a matrix of :class:`Degree` bounds.

    The numerator of any minor using rows I (over the product of those rows'
    common denominators) has degree at most the sum of the contributions of I.
    """
    out = []
    for row in rows:
        entries = [Degree.of(x) for x in row if not _is_zero_constant(x)]
        if not entries:
            out.append(0)
            continue
        lcm = Degree(0)
        for x in entries:
            lcm = lcm + Degree(0, x.den)  # LCM of the denominators
        total = lcm.den_degree
        out.append(max(x.num + total - x.den_degree for x in entries))
    return out


def minor_degree(rows, size: int) -> int:
    """Bound on the numerator degree of every ``size`` x ``size`` minor."""
    contributions = sorted(rank_bound(rows), reverse=True)
    return sum(contributions[:size])


def schwartz_zippel_bound(degree: int, points: int, *, denominator_degree: int = 0,
                          terms: int = 1) -> float:
    """The probability bound of "vanishes at ``points`` random exact points".

    A nonzero rational function whose numerator has degree at most D vanishes at a
    uniformly random point of S^N with probability at most D / |S|; points where a
    denominator of degree D_den vanishes are drawn again, so the bound per point is
    D / (|S| - D_den). ``terms`` functions tested together (a union bound) multiply it.

    Parameters
    ----------
    degree : int
        D, the numerator's degree bound (:class:`Degree`).
    points : int
        k, independent points at which every function vanished.
    denominator_degree : int, optional
        D_den, the degree bound of the denominators that make a point be drawn again.
    terms : int, optional
        How many functions the bound covers.

    Returns
    -------
    float
        terms * min(1, D / (|S| - D_den))^k, |S| = 2^SAMPLE_BITS.
    """
    per = min(1.0, degree / max(1, 2 ** SAMPLE_BITS - denominator_degree))
    return min(1.0, terms * per ** points)


@dataclass(frozen=True)
class ErrorBound:
    """The error bound of verdicts taken at the points of one sampler.

    Called as ``bound(degree, points, terms=1)``: the probability that ``terms``
    functions whose numerators have degree at most ``degree`` and do not vanish
    where the claim says they do all vanish at ``points`` drawn points.

    Two kinds of points:

    * **rational points of a rationally parametrised M** (``variety_degree`` 0): the
      Schwartz–Zippel bound :func:`schwartz_zippel_bound`, ``terms`` * (D / (|S| −
      D_den))^k: the points are independent and uniform in the parameter space, so the
      bounds multiply;
    * **smooth points over F_p of a curved M** (``variety_degree`` = deg X ≥ 1): X is
      the variety of the lifted point (drawn variables, the chart's unknowns and one w
      per sqrt, with w² = radicand), of dimension N (the drawn variables) and degree
      at most the product of its equations' degrees (Bézout). On an irreducible
      component V of X where a function's numerator H (degree ≤ D) is not identically
      zero, V ∩ {H = 0} has dimension N − 1 and degree ≤ deg V · D (Bézout), hence at
      most deg V · D · p^(N−1) points over F_p; a point is bad only when its drawn
      coordinates lie in the projection of those, so a draw is bad with probability
      ≤ deg X · D / (p − 1) (uniform draws in F_p*, up to a factor (p/(p−1))^N < 1 +
      10^-15), and an accepted point, one of at most ``tries`` draws, with probability
      ≤ tries · deg X · D / (p − 1) =: ε. The points may lie on different components,
      so the claim is "on every component of M through the points" and its bound is
      the union ``terms`` · k · ε, not a product.

    Attributes
    ----------
    size : int
        |S|: 2^SAMPLE_BITS for rational points, p − 1 over F_p.
    denominator_degree : int
        D_den of the rational points' redrawn denominators.
    variety_degree : int
        0 for a rational parametrisation; deg X (Bézout number) on a curved M.
    tries : int
        Draws per accepted point on a curved M.
    """

    size: int = 2 ** SAMPLE_BITS
    denominator_degree: int = 0
    variety_degree: int = 0
    tries: int = 1

    def per_point(self, degree: int) -> float:
        """ε: the bound of one point (curved M) or one factor (rational points)."""
        if not self.variety_degree:
            return min(1.0, degree / max(1, self.size - self.denominator_degree))
        return min(1.0, self.tries * self.variety_degree * degree / self.size)

    def __call__(self, degree: int, points: int, terms: int = 1) -> float:
        if not self.variety_degree:
            return schwartz_zippel_bound(degree, points, terms=terms,
                                         denominator_degree=self.denominator_degree)
        return min(1.0, terms * points * self.per_point(degree))

    def describe(self, degree: int) -> str:
        """The bound's formula in words, for a Decision's detail."""
        if not self.variety_degree:
            return f"Schwartz-Zippel, numerator degree <= {degree}"
        return (f"Bezout: per point {self.tries} draws x deg X {self.variety_degree} x "
                f"numerator degree {degree} / (p - 1), summed over the points; on every "
                f"component of M through them")
