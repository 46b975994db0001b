"""Write the scene of a rolling disc whose contact forces are all constraint forces.

Usage::

    python examples/make_disc_on_ground.py [PATH]

writes ``examples/disc_on_ground.toml`` (or PATH; ``-`` for stdout).

A thin uniform disc (mass m, radius r, inertia m r^2/4 (1, 2, 1) about its axes) rolling
without slipping on the plane z = 0, in coordinates that do not build the contact in:
the centre (x, y, z), yaw theta about N.z, lean phi about the heading A.x, spin psi about
the axle B.y. The contact point is P = C - r B.z; its height z - r cos(phi) = 0 is a
holonomic constraint (its lift is the vertical velocity of P) and the two horizontal
components of P's velocity vanish (rolling). So all three components of the ground's
force are constraint forces, and the scene names the point: ``[contacts.ground]`` gives
P's material velocity and the three constraints it carries; ``nhham simulate`` reports
the force along the run. Upright at rest the ground pushes with m g; rolling, the force
minus the weight is m times the centre's acceleration (``tests/numerics/
test_contact_forces.py``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import sympy as sp

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from scene_output import write_example  # noqa: E402
from nhham import System  # noqa: E402
from nhham.system.contacts import ContactPoint  # noqa: E402

VALUES = {"m": 2.0, "g": 9.81, "r": 0.3}


def rotation(axis: int, angle):
    """The rotation matrix about coordinate axis 0, 1 or 2."""
    c, s = sp.cos(angle), sp.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R = sp.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def disc():
    """(System, the contact point) of the disc."""
    x, y, z, th, ph, ps = sp.symbols("x y z theta phi psi")
    xd, yd, zd, thd, phd, psd = sp.symbols("x_dot y_dot z_dot theta_dot phi_dot psi_dot")
    m, g, r = sp.symbols("m g r")
    A = rotation(2, th)
    B = A * rotation(0, ph)
    e = sp.eye(3)
    omega = thd * e[:, 2] + phd * (A * e[:, 0]) + psd * (B * e[:, 1])
    inertia = B * sp.diag(m * r**2 / 4, m * r**2 / 2, m * r**2 / 4) * B.T
    vC = sp.Matrix([xd, yd, zd])
    L = sp.simplify(m * vC.dot(vC) / 2 + (omega.T * inertia * omega)[0] / 2) - m * g * z
    vP = vC + omega.cross(-r * (B * e[:, 2]))
    vP = [sp.expand(sp.simplify(c)) for c in vP]
    system = System([x, y, z, th, ph, ps], L, vP[:2], holonomic=[z - r * sp.cos(ph)],
                    parameters={sp.Symbol(k): v for k, v in VALUES.items()},
                    name="disc on the ground")
    ground = ContactPoint("ground", tuple(vP), ("holonomic[0]", "constraints[0]",
                                                "constraints[1]"))
    return system, ground


def initial_state():
    """Leaning 0.2 rad, turning and rolling: theta_dot 1, phi_dot 0, psi_dot -8; the
    centre's velocity solved from the constraints (z = r cos(phi))."""
    system, _ = disc()
    q = {"x": 0.0, "y": 0.0, "z": VALUES["r"] * float(sp.cos(0.2)), "theta": 0.0,
         "phi": 0.2, "psi": 0.0}
    rates = {"theta_dot": 1.0, "phi_dot": 0.0, "psi_dot": -8.0}
    subs = {s: q[s.name] for s in system.coordinates}
    subs.update({s: rates[s.name] for s in system.velocities if s.name in rates})
    subs.update(system.parameter_values)
    unknown = [s for s in system.velocities if s.name not in rates]
    sol = sp.solve([c.xreplace(subs) for c in system.phi], unknown, dict=True)[0]
    return {**q, **{s.name: float(sol[s]) for s in unknown}, **rates}


HEADER = """# A rolling disc whose contact is a constraint in every direction (written by
# examples/make_disc_on_ground.py): centre (x, y, z), yaw theta, lean phi, spin psi; the
# contact height z - r cos(phi) = 0 is holonomic, the contact point's horizontal velocity
# vanishes (rolling). n = 6, m = 3. [contacts.ground] names the contact point (its
# material velocity) and its three constraints: `nhham simulate` reports the ground's
# force on the disc along the run (JSON "contact_forces"), m g upward at rest.
"""

if __name__ == "__main__":
    system, ground = disc()
    write_example(sys.argv, "disc_on_ground.toml", HEADER, system, initial=initial_state(),
                  contacts=(ground,))
