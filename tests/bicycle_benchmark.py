"""The linearised Whipple bicycle in closed form, independent of nhham.

Meijaard, Papadopoulos, Ruina & Schwab, "Linearized dynamics equations for the balance
and steer of a bicycle: a benchmark and review", Proc. R. Soc. A 463 (2007) 1955-1982,
Appendix A: M q'' + v C1 q' + (g K0 + v^2 K2) q = f with q = (phi, delta), written here
from the paper's formulas for any values of its 25 parameters (z axis down, so the
heights zB, zH are negative). Used by the tests and by ``bench/sweep.py`` (the limit a
sweep is timed against: numpy's eigenvalues of these 4 x 4 state matrices).
"""

from __future__ import annotations

import numpy as np

#: Table 1 of the paper (SI units).
BENCHMARK = dict(
    w=1.02, c=0.08, lam=np.pi / 10, g=9.81,
    rR=0.3, mR=2.0, IRxx=0.0603, IRyy=0.12,
    xB=0.3, zB=-0.9, mB=85.0, IBxx=9.2, IByy=11.0, IBzz=2.8, IBxz=2.4,
    xH=0.9, zH=-0.7, mH=4.0, IHxx=0.05892, IHyy=0.06, IHzz=0.00708, IHxz=-0.00756,
    rF=0.35, mF=3.0, IFxx=0.1405, IFyy=0.28,
)


def benchmark_matrices(p=BENCHMARK):
    """(M, C1, K0, K2), each 2 x 2, from the parameters ``p`` (names of Table 1; each a
    number or a numpy array of equal shapes, the matrices then of shape (..., 2, 2))."""
    w, c, lam = p["w"], p["c"], p["lam"]
    rR, mR, IRxx, IRyy = p["rR"], p["mR"], p["IRxx"], p["IRyy"]
    xB, zB, mB = p["xB"], p["zB"], p["mB"]
    IBxx, IBzz, IBxz = p["IBxx"], p["IBzz"], p["IBxz"]  # (I_Byy enters no equation of lean/steer)
    xH, zH, mH = p["xH"], p["zH"], p["mH"]
    IHxx, IHzz, IHxz = p["IHxx"], p["IHzz"], p["IHxz"]
    rF, mF, IFxx, IFyy = p["rF"], p["mF"], p["IFxx"], p["IFyy"]
    sl, cl = np.sin(lam), np.cos(lam)
    # the whole bicycle (T) and the front assembly (A: fork and front wheel)
    mT = mR + mB + mH + mF
    xT = (xB * mB + xH * mH + w * mF) / mT
    zT = (-rR * mR + zB * mB + zH * mH - rF * mF) / mT
    ITxx = IRxx + IBxx + IHxx + IFxx + mR * rR ** 2 + mB * zB ** 2 + mH * zH ** 2 + mF * rF ** 2
    ITxz = IBxz + IHxz - mB * xB * zB - mH * xH * zH + mF * w * rF
    ITzz = IRxx + IBzz + IHzz + IFxx + mB * xB ** 2 + mH * xH ** 2 + mF * w ** 2
    mA = mH + mF
    xA = (xH * mH + w * mF) / mA
    zA = (zH * mH - rF * mF) / mA
    IAxx = IHxx + IFxx + mH * (zH - zA) ** 2 + mF * (rF + zA) ** 2
    IAxz = IHxz - mH * (xH - xA) * (zH - zA) + mF * (w - xA) * (rF + zA)
    IAzz = IHzz + IFxx + mH * (xH - xA) ** 2 + mF * (w - xA) ** 2
    uA = (xA - w - c) * cl - zA * sl
    IAll = mA * uA ** 2 + IAxx * sl ** 2 + 2 * IAxz * sl * cl + IAzz * cl ** 2
    IAlx = -mA * uA * zA + IAxx * sl + IAxz * cl
    IAlz = mA * uA * xA + IAxz * sl + IAzz * cl
    mu = c / w * cl
    SR, SF = IRyy / rR, IFyy / rF
    ST = SR + SF
    SA = mA * uA + mu * mT * xT
    zero = 0.0 * mu

    def matrix(a, b, c_, d):
        return np.stack([np.stack([a + zero, b + zero], -1), np.stack([c_ + zero, d + zero], -1)],
                        -2)

    M = matrix(ITxx, IAlx + mu * ITxz, IAlx + mu * ITxz, IAll + 2 * mu * IAlz + mu ** 2 * ITzz)
    K0 = matrix(mT * zT, -SA, -SA, -SA * sl)
    K2 = matrix(zero, (ST - mT * zT) / w * cl, zero, (SA + SF * sl) / w * cl)
    C1 = matrix(zero, mu * ST + SF * cl + ITxz / w * cl - mu * mT * zT,
                -(mu * ST + SF * cl), IAlz / w * cl + mu * (SA + ITzz / w * cl))
    return M, C1, K0, K2


def benchmark_state_matrix(v, p=BENCHMARK):
    """A of x' = A x, x = (phi, delta, phi', delta'), at the speed(s) ``v``: shape
    (..., 4, 4) broadcast over ``v`` and the parameters."""
    M, C1, K0, K2 = benchmark_matrices(p)
    v = np.asarray(v, dtype=float)[..., None, None]
    Minv = np.linalg.inv(M)
    K = p["g"] * K0 + v ** 2 * K2
    top = np.broadcast_to(np.concatenate([np.zeros_like(K), np.eye(2) + 0 * K], -1),
                          K.shape[:-2] + (2, 4))
    bottom = np.concatenate([-Minv @ K, -Minv @ (v * C1)], -1)
    return np.concatenate([top, bottom], -2)
