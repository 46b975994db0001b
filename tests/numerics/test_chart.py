"""The complex-step field: the compiled complex kernels against derivatives of the real ones.

The complex kernels (``nhham_saddle_cx_batch``) continue sqrt, powers, atan2, acos, log
and the trigonometric functions to complex arguments; the imaginary part of an output at y + i h e_j, divided by h, must be
the derivative of the real output, here checked against central differences of the real
numpy kernel (no complex arithmetic), to 1e-6 relative.
"""

import numpy as np
import sympy as sp

from nhham import System
from nhham.numerics.chart import ComplexField
from nhham.numerics.codegen import numeric_model
from nhham.numerics.codegen.build import complex_kernels


def _system():
    x, y, th = sp.symbols("x y th")
    xd, yd, thd = sp.symbols("x_dot y_dot th_dot")
    a = sp.Symbol("a")
    # atan2 in W as well as in V (whose derivatives in F are rational)
    L = ((1 + x ** 2) * xd ** 2 / 2 + sp.sqrt(2 + y ** 2) * yd ** 2 / 2
         + (2 + sp.atan2(y, 2 + x)) * thd ** 2 / 2
         - sp.atan2(y, 1 + x ** 2) - sp.log(3 + x) * a - (2 + sp.cos(th)) ** sp.Rational(5, 2)
         - sp.acos(y / 3) * sp.exp(x))
    return System([x, y, th], L, constraints=[xd - sp.sin(th) * yd + a * thd],
                  parameters={"a": 0.7})


def test_complex_kernels_differentiate_like_the_real_ones():
    model = numeric_model(_system())
    # the complex kernels are a library of their own, not in the model's (whose build
    # they would slow several times): built here on first use
    assert model.compiled is not None and "_cx_batch" not in model.c_source
    assert complex_kernels(model) is not None and "saddle_cx" in model.c_complex_source
    cf = ComplexField(model)
    assert cf.backend == "c"
    _differentiates_like_the_real_kernels(cf)


def _differentiates_like_the_real_kernels(cf):
    real = numeric_model(_system(), backend="numpy")
    out = real.kernels.functions["saddle"][1]
    rng = np.random.default_rng(3)
    y0 = rng.uniform(-1, 1, 6)
    h = 1e-30

    def real_outputs(y):
        Y = y[:, None].astype(float)
        o = np.zeros((cf.size, 1))
        out(Y, list(real.parameter_values), o)
        return o[:17, 0]   # W (9), F (3), mu (3), drift (1), h (1)

    for j in range(6):
        Y = y0.astype(complex)
        Y[j] += 1j * h
        W, F, mu, drift, hh, g = cf.pieces(Y[None, :3], Y[None, 3:])
        got = np.concatenate([W.ravel(), F.ravel(), mu.ravel(), drift.ravel(), hh.ravel(),
                              g.ravel()]).imag / h
        e = np.zeros(6)
        e[j] = 1e-6
        fd = (real_outputs(y0 + e) - real_outputs(y0 - e)) / 2e-6
        assert np.allclose(got, fd, rtol=1e-6, atol=1e-7), j
        values = np.concatenate([W.ravel(), F.ravel(), mu.ravel(), drift.ravel(), hh.ravel(),
                                 g.ravel()]).real
        assert np.allclose(values, real_outputs(y0), rtol=1e-14, atol=1e-14)


def test_without_the_compiled_library_numpy_evaluates_the_complex_field():
    """The numpy kernels on complex arrays, atan2 and all (numpy's arctan2 takes no
    complex arrays: a linearisation of a scene with atan2 was an internal error)."""
    model = numeric_model(_system(), backend="numpy")
    cf = ComplexField(model)
    assert cf.backend == "numpy"
    _differentiates_like_the_real_kernels(cf)


def test_complex_kernels_build_with_sympy_s_constants():
    # pi and E print as M_PI and M_E, which -std=c99 hides without _DEFAULT_SOURCE; the
    # complex step of V = pi x^2 + E x is V'(x) = 2 pi x + E
    x, xd = sp.symbols("x x_dot")
    model = numeric_model(System([x], xd ** 2 / 2 - sp.pi * x ** 2 - sp.E * x))
    cf = ComplexField(model, build=True)
    assert cf.backend == "c"
    _, F, *_ = cf.pieces(np.array([[0.3 + 1e-30j]]), np.array([[0.0 + 0j]]))
    assert abs(F[0, 0].imag / 1e-30 - (-2 * np.pi)) < 1e-12   # dF/dx, F = -V'(x)
    assert abs(F[0, 0].real - (-(2 * np.pi * 0.3 + np.e))) < 1e-12


def test_complex_kernels_are_compiled_at_O0_with_the_results_of_O2(monkeypatch):
    """The complex kernels' level (-O0: GCC's register allocation at -O2 takes 18 s on the
    bicycle's) changes no output bit: IEEE arithmetic at either level."""
    from nhham.numerics.codegen.build import OPTIMIZE, OPTIMIZE_COMPLEX, Compilation, build
    from nhham.numerics.codegen.cache import CompileCache
    from nhham.numerics.kernels import ComplexKernels

    monkeypatch.delenv("NHHAM_CFLAGS", raising=False)   # the suite's own -O0
    model = numeric_model(_system())
    assert (OPTIMIZE, OPTIMIZE_COMPLEX) == ("-O2", "-O0")
    cache = CompileCache.open(None)
    kernels = {}
    for level in ("-O0", "-O2"):
        job = Compilation.of(model.c_complex_source, tag="complex", optimize=level)
        assert job.flags[0] == level and not any(f.startswith("-O") for f in job.flags[1:])
        kernels[level] = ComplexKernels.load(build(cache, job), model.layout)
    rng = np.random.default_rng(5)
    Y = rng.uniform(-1, 1, (64, 6)) + 1j * rng.uniform(-1e-3, 1e-3, (64, 6))
    P = np.array(model.parameter_values, dtype=float)
    n, m, k = (model.layout[key] for key in "nmk")
    read = n * n + n + m * n + 2 * m + k   # W, F, mu, drift, h, g (ComplexField.pieces)
    a, b = (kernels[level].complex_batch("saddle", Y, P)[:, :read]
            for level in ("-O0", "-O2"))
    assert np.isfinite(a).all() and np.array_equal(a, b)
