"""Write the scene of a roller racer with a thrust motor, drag and a joint motor, built with
sympy.physics.mechanics.

Usage::

    python examples/make_roller_racer.py [PATH]

writes ``examples/roller_racer.toml`` (or PATH; ``-`` for stdout).

The roller racer (Krishnaprasad and Tsakiris, "Oscillations, SE(2)-snakes and motion
control", 2001; Bloch, "Nonholonomic Mechanics and Control", §1.11): two planar bodies
joined by a revolute joint, each on a pair of wheels at its centre of mass that does not
slip sideways. The front body (mass m1, inertia I1 about its centre C1, heading theta)
carries the joint J at d1 behind C1; the rear body (mass m2, inertia I2, heading
theta + phi) has its centre C2 at d2 behind J. Coordinates: x, y of C1, theta, the joint
angle phi. Constraints: no side slip at C1 and at C2 (2 affine constraints, n = 4).

Forces: a thrust F (an input) at C1 along the front body's axis; viscous drag -c v on
each centre (the drag of the air and of the wheels' bearings, the same coefficient c);
a joint motor torque tau (an input) on the rear body and -tau on the front one, so the
generalized force on phi is tau.

Steady motion: straight ahead at speed U (theta = phi = 0, x' = U) with the thrust
balancing the drag of both bodies, F = 2 c U (both centres move at U; tau = 0). The
[control] laws hold the thrust at F = 2 c U and servo the joint straight,
tau = -kp phi - kd phi'.

Linearised about it (by hand, with the no-slip constraints: at phi = 0 the rear
constraint reads (d1 + d2) theta' + d2 phi' = -U phi to first order, and the forward
speed v decouples): in the chart (x, y, theta, phi, x', phi') the forward speed obeys
(m1 + m2) v' = F - 2 c v, the eigenvalue -2 c / (m1 + m2) (see
tests/numerics/test_roller_racer.py for the whole matrix from sympy's KanesMethod).
"""

from __future__ import annotations

import sys
from pathlib import Path

import sympy as sp
from sympy.physics import mechanics as me

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from nhham.system.description import System  # noqa: E402
from nhham.system.mechanics import from_mechanics  # noqa: E402

VALUES = {"m1": 2.0, "I1": 0.1, "m2": 1.5, "I2": 0.08, "d1": 0.4, "d2": 0.3, "c": 0.5,
          "U": 1.0, "kp": 2.0, "kd": 0.5}


def mechanics_system(forces=True):
    """The sympy.physics.mechanics.System of the roller racer and its inputs (F, tau)."""
    x, y, theta, phi = me.dynamicsymbols("x y theta phi")
    F, tau = me.dynamicsymbols("F tau")
    m1, I1, m2, I2, d1, d2, c = sp.symbols("m1 I1 m2 I2 d1 d2 c")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    B1 = N.orientnew("B1", "Axis", [theta, N.z])        # front body: B1.x forward
    B2 = B1.orientnew("B2", "Axis", [phi, B1.z])        # rear body
    C1 = O.locatenew("C1", x * N.x + y * N.y)
    J = C1.locatenew("J", -d1 * B1.x)
    C2 = J.locatenew("C2", -d2 * B2.x)
    bodies = [me.RigidBody("front", C1, B1, m1, (me.inertia(B1, 0, 0, I1), C1)),
              me.RigidBody("rear", C2, B2, m2, (me.inertia(B2, 0, 0, I2), C2))]
    v1, v2 = C1.pos_from(O).dt(N), C2.pos_from(O).dt(N)
    msys = me.System(N, O)
    msys.contact_velocities = {"front": v1.to_matrix(N), "rear": v2.to_matrix(N)}
    msys.add_coordinates(x, y, theta, phi)
    msys.add_bodies(*bodies)
    msys.add_nonholonomic_constraints(v1.dot(B1.y), v2.dot(B2.y))
    if forces:
        msys.add_loads(me.Force(C1, F * B1.x - c * v1), me.Force(C2, -c * v2),
                       me.Torque(B2, tau * N.z), me.Torque(B1, -tau * N.z))
    return msys, (F, tau)


def build(values=None, forces=True):
    """The nhham System of the roller racer, from its sympy.physics.mechanics.System."""
    msys, inputs = mechanics_system(forces)
    values = dict(values or VALUES)
    system = from_mechanics(msys, parameters=values, inputs=inputs if forces else (),
                            name="roller racer with thrust, drag and a joint motor"
                            if forces else "roller racer")
    tidy = [sp.trigsimp(sp.expand(e)) for e in system.constraints]
    q = [sp.trigsimp(sp.expand(e)) for e in system.generalized_forces] if forces else None
    return System(system.coordinates, sp.trigsimp(sp.expand(system.lagrangian)),
                  constraints=tidy, parameters=values, name=system.name,
                  forces=q, inputs=system.inputs)


def contacts():
    """The wheel pairs' contact points, at the centres C1 and C2: their velocities (the
    material velocity of the axle's midpoint) and the no-slip constraint each carries."""
    from nhham.system.contacts import ContactPoint

    msys, _ = mechanics_system()
    t = me.dynamicsymbols._t
    plain = {qi.diff(t): sp.Symbol(f"{qi.func.__name__}_dot") for qi in msys.q}
    plain.update({qi: sp.Symbol(qi.func.__name__) for qi in msys.q})
    out = []
    for j, (name, v) in enumerate(msys.contact_velocities.items()):
        components = [sp.trigsimp(sp.expand(e.subs(plain))) for e in v]
        out.append(ContactPoint(name, tuple(components), (f"constraints[{j}]",)))
    return out


STEADY = {"F": "2*c*U", "tau": "0", "x": "0", "y": "0", "theta": "0", "phi": "0",
          "x_dot": "U", "y_dot": "0", "theta_dot": "0", "phi_dot": "0"}
CONTROL = {"F": "2*c*U", "tau": "-kp*phi - kd*phi_dot"}
# The independent values only: y_dot and theta_dot are solved from the constraints.
INITIAL = {"x": 0.0, "y": 0.0, "theta": 0.0, "phi": 0.3, "x_dot": 0.5, "phi_dot": 0.0}

HEADER = """\
# A roller racer (Krishnaprasad and Tsakiris 2001; written by examples/make_roller_racer.py
# from a sympy.physics.mechanics.System): a front body (x, y: its centre C1, heading theta)
# and a rear body joined at J, d1 behind C1, by a revolute joint (angle phi); the rear
# centre C2 is d2 behind J. Each body rolls on a wheel pair at its centre that does not slip
# sideways: n = 4, m = 2. A thrust F (input) pushes the front body along its axis, each
# centre feels a viscous drag -c v, a joint motor applies tau (input) between the bodies.
# The [control] laws hold the thrust at 2 c U and servo the joint, tau = -kp phi - kd phi'.
#
# What `nhham classify` reports: C regular on M_1 (rank 2, exact), one stage, determined,
#   no free multipliers, not integrable; on T*Q 2 second class.
# What `nhham linearize` finds about the [steady] straight run at speed U (thrust 2 c U
#   against the drag of both centres): neutral x, y, theta; the speed decays at
#   -2 c / (m1 + m2) = -0.2857 (by hand); with the joint servo the joint's pair is
#   -5.5734 +- 3.9772i (asymptotically stable); the open loop (a free joint, tau = 0) is
#   unstable, 0.04587 +- 1.3873i; its B has 2 columns (F, tau), the closed loop's none.
#   A and B against sympy's KanesMethod to 1e-8 in tests/numerics/test_roller_racer.py.
# What `nhham simulate` does from [initial] (only x_dot and phi_dot given with the
#   coordinates: y_dot and theta_dot are solved from the constraints and named): the joint
#   straightens and the racer runs on at speed U (end states against KanesMethod and
#   solve_ivp to 1e-8 in tests/numerics/test_roller_racer.py). [contacts]: the side forces
#   of the wheel pairs at C1 and C2 (against the momentum balance of the whole racer to
#   1e-12; a planar model, so simulate warns that each point's velocity map has rank 2).
"""


def main(argv):
    from nhham.system.scene import loads_scene
    from scene_output import SIMULATE, write_scene

    from nhham.system.scene_dump import dump_scene

    # dump_scene writes no [control] (not part of a System): appended before [simulate].
    text = dump_scene(build(), simulate=SIMULATE, steady=STEADY, contacts=contacts())
    head, tail = text.split("\n[simulate]\n")
    control = "".join(f'{k} = "{v}"\n' for k, v in CONTROL.items())
    initial = "".join(f"{k} = {v!r}\n" for k, v in INITIAL.items())
    text = (HEADER + head + "\n[initial]\n" + initial + "\n[control]\n" + control
            + "\n[simulate]\n" + tail)
    loads_scene(text)   # it reads back
    target = argv[1] if len(argv) > 1 else str(Path(__file__).resolve().parent
                                               / "roller_racer.toml")
    write_scene(text, target)


if __name__ == "__main__":
    main(sys.argv)
