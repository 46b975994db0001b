"""Write the scene of the Whipple-Carvallo bicycle, built with sympy.physics.mechanics.

Usage::

    python examples/make_whipple_bicycle.py [PATH]

writes ``examples/whipple_bicycle.toml`` (or PATH; ``-`` for standard
output).

The model is the benchmark bicycle of Meijaard, Papadopoulos, Ruina & Schwab,
"Linearized dynamics equations for the balance and steer of a bicycle: a
benchmark and review", Proc. R. Soc. A 463 (2007) 1955-1982, set up as in
sympy's own ``sympy/physics/mechanics/tests/test_kane3.py`` (the same frames,
the same parameterisation of the frame and fork by the head-tube angle and
the same numbers converted from the paper), but written the way nhham needs
it: every configuration variable is a coordinate (rear contact x, y and both
wheel angles included, where the Kane model leaves them out because it sets
the contact velocity to zero by hand), bodies and gravity go in as a
``sympy.physics.mechanics.System``, and the rolling constraints are written
in the generalized speeds u with the kinematic differential equations
q' = u, as ``KanesMethod`` takes them. :func:`nhham.from_mechanics` turns
that into L = T - V and constraints in (q, q').

Coordinates (names in the scene):

    x, y     rear-wheel contact point in the ground plane
    psi      yaw of the rear frame
    phi      lean (roll) of the rear frame
    pitch    pitch of the rear frame, measured from the nominal upright pitch;
             dependent through the holonomic constraint
    thetaR   rear wheel rotation relative to the rear frame
    delta    steer angle (fork relative to the rear frame)
    thetaF   front wheel rotation relative to the fork

Constraints: the front contact point stays on the ground (one holonomic
constraint); neither wheel slips, longitudinally or laterally (four affine
constraints). n = 8, m = 5 velocity constraints (the holonomic one counted by
its time derivative): 3 degrees of freedom in velocity (rear wheel rate,
lean rate, steer rate).

Forward speed is the parameter ``v``: the ``[steady]`` table states the
upright straight-ahead steady motion x' = v, thetaR' = v/rR,
thetaF' = v/rF, everything else zero.
"""

from __future__ import annotations

import sys
from pathlib import Path

import sympy as sp
from sympy.physics import mechanics as me

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from scene_output import write_example  # noqa: E402
from nhham.system.description import System, quadratic_parts  # noqa: E402
from nhham.system.contacts import ContactPoint  # noqa: E402
from nhham.system.mechanics import from_mechanics  # noqa: E402

#: Benchmark values (Meijaard et al. 2007, Table 1), converted to the
#: parameterisation of sympy's test_kane3.py exactly as that test does.
_PAPER = dict(rR=0.3, rF=0.35, lam=sp.pi / 10, trail=0.08, wheelbase=1.02,
              xB=0.3, zB=0.9, xH=0.9, zH=0.7)


def benchmark_parameters() -> dict:
    """Parameter values of the benchmark bicycle in this model's names."""
    p = _PAPER
    HTA = (sp.pi / 2 - p["lam"]).evalf(30)
    rake = (-(p["trail"] * sp.sin(HTA) - (p["rF"] * sp.cos(HTA)))).evalf(30)
    framelength = (p["wheelbase"] * sp.sin(HTA)
                   - (rake - (p["rF"] - p["rR"]) * sp.cos(HTA))).evalf(30)
    framecg_norm = ((p["zB"] - p["rR"] - (p["xB"] / sp.sin(HTA)) * sp.cos(HTA))
                    * sp.sin(HTA)).evalf(30)
    framecg_par = (p["xB"] / sp.sin(HTA) + (p["zB"] - p["rR"] - p["xB"] / sp.sin(HTA)
                                             * sp.cos(HTA)) * sp.cos(HTA)).evalf(30)
    ta = p["zH"] - p["rF"]
    tb = p["wheelbase"] - p["xH"]
    tc = sp.sqrt(ta ** 2 + tb ** 2).evalf(30)
    forklength = (p["wheelbase"] * sp.cos(HTA) - (p["rF"] - p["rR"]) * sp.sin(HTA)).evalf(30)
    forkcg_norm = (rake + (tc * sp.sin(sp.pi / 2 - HTA - sp.acos(ta / tc)))).evalf(30)
    forkcg_par = (tc * sp.cos((sp.pi / 2 - HTA) - sp.acos(ta / tc)) - forklength).evalf(30)
    values = {
        "rF": p["rF"], "rR": p["rR"], "htangle": HTA, "forkoffset": rake,
        "forklength": forklength, "framelength": framelength,
        "forkcg1": forkcg_par, "forkcg3": forkcg_norm,
        "framecg1": framecg_norm, "framecg3": framecg_par,
        "Iwr11": 0.0603, "Iwr22": 0.12, "Iwf11": 0.1405, "Iwf22": 0.28,
        "Ifork11": 0.05892, "Ifork22": 0.06, "Ifork33": 0.00708, "Ifork31": 0.00756,
        "Iframe11": 9.2, "Iframe22": 11.0, "Iframe33": 2.8, "Iframe31": -2.4,
        "mfork": 4.0, "mframe": 85.0, "mwf": 3.0, "mwr": 2.0, "g": 9.81,
    }
    return {k: float(v) for k, v in values.items()}


def mechanics_system() -> me.System:
    """The bicycle as a ``sympy.physics.mechanics.System`` (bodies, gravity, u-form constraints)."""
    return mechanics_model()[0]


def mechanics_model():
    """(the mechanics System, its contact points): the contact points as
    ``(name, material velocity in N as three expressions in q(t), q'(t), labels, the
    contact Point)``."""
    x, y, psi, phi, pitch, thetaR, delta, thetaF = me.dynamicsymbols(
        "x y psi phi pitch thetaR delta thetaF")
    q = [x, y, psi, phi, pitch, thetaR, delta, thetaF]
    u = me.dynamicsymbols("u1:9")
    (rF, rR, htangle, forkoffset, forklength, framelength, forkcg1, forkcg3, framecg1,
     framecg3) = sp.symbols("rF rR htangle forkoffset forklength framelength forkcg1 forkcg3 "
                            "framecg1 framecg3")
    Iwr11, Iwr22, Iwf11, Iwf22 = sp.symbols("Iwr11 Iwr22 Iwf11 Iwf22")
    Iframe11, Iframe22, Iframe33, Iframe31 = sp.symbols("Iframe11 Iframe22 Iframe33 Iframe31")
    Ifork11, Ifork22, Ifork33, Ifork31 = sp.symbols("Ifork11 Ifork22 Ifork33 Ifork31")
    mframe, mfork, mwf, mwr, g = sp.symbols("mframe mfork mwf mwr g")

    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    # Frames as in test_kane3.py: yaw about N.z (up), lean about Y.x, the rear
    # frame pitched by htangle about R.y, steer about the head tube Frame.x.
    Y = N.orientnew("Y", "Axis", [psi, N.z])
    R = Y.orientnew("R", "Axis", [phi, Y.x])
    Frame = R.orientnew("Frame", "Axis", [pitch + htangle, R.y])
    TempFrame = Frame.orientnew("TempFrame", "Axis", [-htangle, Frame.y])
    Fork = Frame.orientnew("Fork", "Axis", [delta, Frame.x])
    TempFork = Fork.orientnew("TempFork", "Axis", [-htangle, Fork.y])
    WR = Frame.orientnew("WR", "Axis", [thetaR, Frame.y])
    WF = Fork.orientnew("WF", "Axis", [thetaF, Fork.y])

    WR_cont = O.locatenew("WR_cont", x * N.x + y * N.y)
    WR_mc = WR_cont.locatenew("WR_mc", rR * R.z)
    Steer = WR_mc.locatenew("Steer", framelength * Frame.z)
    Frame_mc = WR_mc.locatenew("Frame_mc", -framecg1 * Frame.x + framecg3 * Frame.z)
    Fork_mc = Steer.locatenew("Fork_mc", -forkcg1 * Fork.x + forkcg3 * Fork.z)
    WF_mc = Steer.locatenew("WF_mc", forklength * Fork.x + forkoffset * Fork.z)
    # Front contact: from the wheel centre, down the wheel plane towards the ground.
    down = (me.dot(Fork.y, Y.z) * Fork.y - Y.z)
    WF_cont = WF_mc.locatenew("WF_cont", rF * down / sp.sqrt(1 - me.dot(Fork.y, Y.z) ** 2))

    bodies = [
        me.RigidBody("frame", Frame_mc, Frame, mframe,
                     (me.inertia(TempFrame, Iframe11, Iframe22, Iframe33, 0, 0, Iframe31),
                      Frame_mc)),
        me.RigidBody("fork", Fork_mc, Fork, mfork,
                     (me.inertia(TempFork, Ifork11, Ifork22, Ifork33, 0, 0, Ifork31), Fork_mc)),
        me.RigidBody("rear_wheel", WR_mc, WR, mwr, (me.inertia(Frame, Iwr11, Iwr22, Iwr11), WR_mc)),
        me.RigidBody("front_wheel", WF_mc, WF, mwf, (me.inertia(Fork, Iwf11, Iwf22, Iwf11), WF_mc)),
    ]

    # Kinematic differential equations q' = u, and the rolling constraints
    # written in u: the velocity of each wheel's material point at its
    # contact vanishes along the ground directions Y.x, Y.y.
    t = me.dynamicsymbols._t
    qd_to_u = {qi.diff(t): ui for qi, ui in zip(q, u)}
    kdes = [qi.diff(t) - ui for qi, ui in zip(q, u)]

    def contact_velocity(centre, wheel, contact):
        v_centre = centre.pos_from(O).dt(N)
        return v_centre + me.cross(wheel.ang_vel_in(N), contact.pos_from(centre))

    v_rear = contact_velocity(WR_mc, WR, WR_cont)
    v_front = contact_velocity(WF_mc, WF, WF_cont)
    nonholonomic = [sp.trigsimp(v_rear.dot(Y.x)), sp.trigsimp(v_rear.dot(Y.y)),
                    v_front.dot(Y.x), v_front.dot(Y.y)]
    nonholonomic = [c.xreplace(qd_to_u) for c in nonholonomic]
    holonomic = [WF_cont.pos_from(WR_cont).dot(Y.z)]

    system = me.System(N, O)
    system.add_coordinates(*q)
    system.add_speeds(*u)
    system.add_kdes(*kdes)
    system.add_bodies(*bodies)
    system.add_holonomic_constraints(*holonomic)
    system.add_nonholonomic_constraints(*nonholonomic)
    system.add_loads(*[me.Force(b.masscenter, -b.mass * g * N.z) for b in bodies])
    # Each wheel's material point at its contact: the rear carries the two rolling
    # constraints (its height is built into the coordinates, so its normal force is no
    # constraint force), the front also the lift of the contact height.
    contacts = [("rear", [v_rear.dot(N.x), v_rear.dot(N.y), v_rear.dot(N.z)],
                 ("constraints[0]", "constraints[1]"), WR_cont),
                ("front", [v_front.dot(N.x), v_front.dot(N.y), v_front.dot(N.z)],
                 ("holonomic[0]", "constraints[2]", "constraints[3]"), WF_cont)]
    return system, contacts


def build():
    """The nhham System of the benchmark bicycle (parameters with values, plus v).

    L = T - V from :func:`nhham.from_mechanics` is rewritten term by term as
    the quadratic form sum_{A<=B} c_AB v^A v^B - V (the same function, each
    coefficient gathered once): smaller to print and to differentiate.
    """
    values = benchmark_parameters()
    values["v"] = 5.0
    model, _ = mechanics_model()
    system = from_mechanics(model, parameters=values, name="Whipple bicycle")
    parts = quadratic_parts(system.lagrangian, system.velocities)
    vs, W = system.velocities, parts.W
    L = -parts.V
    for A in range(system.n):
        L += W[A, A] * vs[A] ** 2 / 2
        for B in range(A + 1, system.n):
            L += W[A, B] * vs[A] * vs[B]
    return System(system.coordinates, L, constraints=system.constraints,
                  holonomic=system.holonomic, parameters=values, name=system.name)


STEADY = {
    "x": "0", "y": "0", "psi": "0", "phi": "0", "pitch": "0", "thetaR": "0", "delta": "0",
    "thetaF": "0",
    "x_dot": "v", "y_dot": "0", "psi_dot": "0", "phi_dot": "0", "pitch_dot": "0",
    "thetaR_dot": "v/rR", "delta_dot": "0", "thetaF_dot": "v/rF",
}

HEADER = """\
# The Whipple-Carvallo bicycle, benchmark parameters of Meijaard, Papadopoulos, Ruina &
# Schwab, Proc. R. Soc. A 463 (2007) 1955-1982 (written by examples/make_whipple_bicycle.py
# from a sympy.physics.mechanics model; frames and parameter conversion as in sympy's
# sympy/physics/mechanics/tests/test_kane3.py). Forward speed: the parameter v.
# x, y = rear contact; psi yaw, phi lean, pitch (from the nominal upright pitch; dependent),
# thetaR rear wheel angle, delta steer, thetaF front wheel angle. Front contact on the ground
# (holonomic), no slip at either wheel (4 affine constraints): n = 8, m = 5.
#
# What `nhham classify` reports: C regular on M_1 (rank 5), one stage (M_f = M_1),
#   determined, no free multipliers, not integrable (rolling); on T*Q 0 first class, 6 second
#   class: every decision proved at a smooth point of the curved M_1 over F_p with the
#   parameters at their values (about 2.7 s CPU, bench/RESULTS.md).
# What `nhham linearize` finds about the [steady] upright straight-ahead motion: neutral
#   directions x, y, psi, thetaR, thetaF (cyclic) and the speed (thetaF_dot in the chart
#   chosen: pitch, x_dot, y_dot, psi_dot, pitch_dot, thetaR_dot dependent); in the
#   independent coordinates phi, delta, phi_dot, delta_dot the 4x4 state matrix of the
#   benchmark (eigenvalues to 1e-8 against the paper's M, C1, K0, K2, tests/numerics/
#   test_linearize.py). `nhham linearize examples/whipple_bicycle.toml --sweep v=0:10:101`
#   finds the weave speed 4.292382 m/s (complex pair crossing) and the capsize speed
#   6.024262 m/s (real crossing): self-stable between them (paper, section 6).
"""


def initial_state():
    """The steady motion at v = 5 m/s with a lean rate of 0.5 rad/s added (on M_1 exactly:
    at the upright state the lean rate enters no constraint)."""
    values = benchmark_parameters()
    state = {k: 0.0 for k in STEADY}
    state.update(x_dot=5.0, thetaR_dot=5.0 / values["rR"], thetaF_dot=5.0 / values["rF"],
                 phi_dot=0.5)
    return state


def contact_points(system) -> tuple:
    """The wheels' contact points in the scene's symbols (q, q_dot)."""
    _, contacts = mechanics_model()
    t = me.dynamicsymbols._t
    names = {s.name: s for s in (*system.coordinates, *system.velocities)}
    out = []
    for name, velocity, labels, _ in contacts:
        exprs = []
        for e in velocity:
            funcs = sorted(e.atoms(sp.Function), key=str)
            rates = {f.diff(t): names[f"{f.func.__name__}_dot"] for f in funcs
                     if f.func.__name__ in names}
            e = e.subs(rates).subs({f: names[f.func.__name__] for f in funcs
                                    if f.func.__name__ in names})
            exprs.append(sp.expand(e))
        out.append(ContactPoint(name, tuple(exprs), labels))
    return tuple(out)


def main(argv):
    system = build()
    write_example(argv, "whipple_bicycle.toml", HEADER, system, initial=initial_state(),
                  steady=STEADY, contacts=contact_points(system),
                  description="Whipple bicycle, Meijaard et al. (2007) benchmark; forward speed v")


if __name__ == "__main__":
    main(sys.argv)
