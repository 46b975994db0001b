"""Expressions to numbers (nhham.system.evaluation): one route, three backends.

Values are compared with sympy's own evaluation (evalf at 30 digits) and, for residues
modulo p, with the reduction of the exact rational value.
"""

import mpmath
import numpy as np
import pytest
import sympy as sp
from sympy.external.gmpy import MPQ

from nhham.lagrangian.domains import ModP
from nhham.lagrangian.linalg import ModularBackend
from nhham.system.evaluation import Backend, Lambdified, numeric_function, object_solve

x, y = sp.symbols("x y")
EXPRS = [x**2 * y - 3, sp.Rational(1, 3) * x + y / 7, x * y]


def test_float_and_mpmath_agree_with_sympy():
    f = Lambdified((x, y), EXPRS, (3,))
    at = {x: sp.Rational(2, 5), y: sp.Rational(-7, 3)}
    want = [sp.N(e.subs(at), 30) for e in EXPRS]
    got64 = f(Backend(None), [0.4, -7 / 3])
    assert got64.dtype == float and np.allclose(got64, [float(w) for w in want], rtol=1e-15)
    with mpmath.workdps(30):
        got30 = f(Backend(30), [mpmath.mpf(2) / 5, mpmath.mpf(-7) / 3])
        assert all(abs(g - mpmath.mpf(str(w))) < mpmath.mpf(10) ** -27
                   for g, w in zip(got30, want))


def _residue(r):
    r = sp.Rational(r)
    return ModP.lift(MPQ(int(r.p), int(r.q)))


def test_the_modular_backend_reduces_the_exact_value():
    f = Lambdified((x, y), EXPRS, (3,))
    got = f(ModularBackend(), [_residue("2/5"), _residue("-7/3")])
    exact = [e.subs({x: sp.Rational(2, 5), y: sp.Rational(-7, 3)}) for e in EXPRS]
    assert list(got) == [_residue(v) for v in exact]


def test_object_solve_solves_in_mpmath():
    rng = np.random.default_rng(3)
    A = rng.normal(size=(4, 4)) + 4 * np.eye(4)
    B = rng.normal(size=(4, 2))
    with mpmath.workdps(40):
        Ao = np.array([[mpmath.mpf(float(v)) for v in r] for r in A], dtype=object)
        Bo = np.array([[mpmath.mpf(float(v)) for v in r] for r in B], dtype=object)
        X = object_solve(Ao, Bo)
        residual = max(abs(v) for v in (Ao @ X - Bo).ravel())
    assert residual < mpmath.mpf(10) ** -35
    assert np.allclose(np.array(X, dtype=float), np.linalg.solve(A, B), rtol=1e-12)


def test_numeric_function_keeps_the_nesting():
    f = numeric_function((x, y), sp.Matrix([[x, y], [x * y, 1]]))
    assert np.array(f(2.0, 3.0)).tolist() == [[2.0, 3.0], [6.0, 1.0]]
    with pytest.raises(ZeroDivisionError):
        object_solve(np.zeros((2, 2), dtype=object), np.ones(2, dtype=object))


def test_numeric_functions_keep_ieee_arithmetic_on_python_floats():
    """y**(-1.0) at y = 0.0: Python's float power raised ZeroDivisionError (an internal
    error where a sample point met the pole); numpy's gives inf, which the callers read
    as "not finite there"."""
    import numpy as np
    import sympy as sp

    from nhham.system.evaluation import numeric_function

    y = sp.Symbol("y")
    f = numeric_function([y], [y ** -1.0, sp.sqrt(y)])
    with np.errstate(all="ignore"):
        assert f(0.0) == [np.inf, 0.0] and f(4.0) == [0.25, 2.0]
