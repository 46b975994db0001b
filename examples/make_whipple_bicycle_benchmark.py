"""Write the Whipple bicycle in the benchmark's own parameters (trail, head angle, ...).

Usage::

    python examples/make_whipple_bicycle_benchmark.py [PATH]

writes ``examples/whipple_bicycle_benchmark.toml`` (or PATH; ``-`` for standard output).

The model is that of ``make_whipple_bicycle.py`` (the same bodies, frames and
constraints), with its frame-and-fork parameters (head-tube angle, fork offset,
lengths, mass-centre offsets: those of sympy's ``test_kane3.py``) replaced by the
expressions that convert the 25 parameters of Meijaard et al. (2007, Table 1) into them,
so that a study can move the trail ``c``, the head angle ``lam`` or the wheelbase ``w``
and everything they determine moves with it. The names and signs are the paper's (z axis
down: the heights ``zB``, ``zH`` are negative); ``pitch = 0`` is upright for every value
of them (the conversion keeps the nominal configuration), so the ``[steady]`` table is
the same as the other scene's.
"""

from __future__ import annotations

import sys
from pathlib import Path

import sympy as sp

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from make_whipple_bicycle import STEADY, benchmark_parameters, build  # noqa: E402
from scene_output import write_example  # noqa: E402
from nhham.system.description import System  # noqa: E402

#: Table 1 of Meijaard et al. (2007), in the paper's names and signs (lam = pi/10).
PAPER = dict(
    w=1.02, c=0.08, lam=0.3141592653589793, g=9.81,
    rR=0.3, mR=2.0, IRxx=0.0603, IRyy=0.12,
    xB=0.3, zB=-0.9, mB=85.0, IBxx=9.2, IByy=11.0, IBzz=2.8, IBxz=2.4,
    xH=0.9, zH=-0.7, mH=4.0, IHxx=0.05892, IHyy=0.06, IHzz=0.00708, IHxz=-0.00756,
    rF=0.35, mF=3.0, IFxx=0.1405, IFyy=0.28,
)


def conversion() -> dict:
    """{parameter of the frame-and-fork model: expression in the paper's parameters}.

    The conversion of sympy's ``test_kane3.py`` with its angles written out (the head-tube
    angle is pi/2 - lam; the fork's mass-centre offsets use cos and sin of
    acos(ta/tc) = ta/tc and tb/tc, so no square root is left).
    """
    s = {k: sp.Symbol(k) for k in PAPER}
    w, c, lam, rR, rF = s["w"], s["c"], s["lam"], s["rR"], s["rF"]
    sl, cl = sp.sin(lam), sp.cos(lam)
    rake = rF * sl - c * cl
    forklength = w * sl - (rF - rR) * cl
    ta, tb = -s["zH"] - rF, w - s["xH"]   # height of the fork's centre above the front axle
    return {
        "htangle": sp.pi / 2 - lam,
        "forkoffset": rake,
        "framelength": (w + c) * cl - rR * sl,
        "forklength": forklength,
        "framecg1": (-s["zB"] - rR) * cl - s["xB"] * sl,
        "framecg3": s["xB"] * cl + (-s["zB"] - rR) * sl,
        "forkcg1": ta * cl + tb * sl - forklength,
        "forkcg3": rake + ta * sl - tb * cl,
        "Iwr11": s["IRxx"], "Iwr22": s["IRyy"], "Iwf11": s["IFxx"], "Iwf22": s["IFyy"],
        "Ifork11": s["IHxx"], "Ifork22": s["IHyy"], "Ifork33": s["IHzz"],
        "Ifork31": -s["IHxz"],
        "Iframe11": s["IBxx"], "Iframe22": s["IByy"], "Iframe33": s["IBzz"],
        "Iframe31": -s["IBxz"],
        "mframe": s["mB"], "mfork": s["mH"], "mwf": s["mF"], "mwr": s["mR"],
        "rR": rR, "rF": rF, "g": s["g"],
    }


def build_benchmark() -> System:
    """The bicycle of ``make_whipple_bicycle.build()`` in the paper's parameters (plus v)."""
    system = build()
    old = {p.name: p for p in system.parameters}
    rules = {old[k]: e for k, e in conversion().items() if k in old and str(e) != k}
    numbers = benchmark_parameters()
    for k, e in conversion().items():   # the conversion reproduces the other scene's values
        value = float(e.subs({sp.Symbol(n): v for n, v in PAPER.items()}))
        assert abs(value - numbers[k]) <= 1e-12 * max(1.0, abs(numbers[k])), (k, value)
    values = dict(PAPER, v=5.0)

    def convert(expr):
        return expr.xreplace(rules)

    return System(system.coordinates, convert(system.lagrangian),
                  constraints=[convert(e) for e in system.constraints],
                  holonomic=[convert(e) for e in system.holonomic], parameters=values,
                  name="Whipple bicycle (benchmark parameters)")


HEADER = """\
# The Whipple-Carvallo bicycle in the 25 parameters of Meijaard, Papadopoulos, Ruina &
# Schwab, Proc. R. Soc. A 463 (2007) 1955-1982, Table 1, with their names and signs (z
# down: zB, zH < 0; lam the steer axis tilt, c the trail, w the wheelbase), plus the
# forward speed v (written by examples/make_whipple_bicycle_benchmark.py: the model of
# whipple_bicycle.toml with its frame-and-fork parameters replaced by their expressions in
# these). For studies that move the trail, the head angle or a mass:
#   nhham sweep examples/whipple_bicycle_benchmark.toml --what linearize \\
#       --over v=0:10:201 --over c=0:0.2:101 --out map.zarr
# What `nhham classify` reports: as for whipple_bicycle.toml (C regular on M_1, rank 5,
#   one stage, determined, not integrable; on T*Q 0 first class, 6 second class).
# What `nhham linearize` finds: the benchmark's weave speed 4.292382 m/s and capsize speed
#   6.024262 m/s at c = 0.08 (as whipple_bicycle.toml, which has the same values); at any
#   trail, head angle or mass the eigenvalues of the closed form of the paper's Appendix A
#   (tests/numerics/test_batch_linearization.py).
"""


def main(argv):
    system = build_benchmark()
    write_example(argv, "whipple_bicycle_benchmark.toml", HEADER, system, steady=STEADY,
                  description="Whipple bicycle in the benchmark's parameters; forward speed v")


if __name__ == "__main__":
    main(sys.argv)
