"""The rolling disc in 3-D, built the way sympy.physics.mechanics users build it.

Yaw q1, lean q2, spin q3 (body-fixed rotations Z, X, Y), contact point x, y on
the ground plane; a thin uniform disc of mass m and radius r rolling without
slipping. L = T - V from ``Lagrangian(N, disc)`` with V = m g (height of the
centre); the two rolling constraints say that the material point of the disc
at the contact has zero velocity in the ground frame. Returns the nhham System
(n = 5, m = 2) and the pieces for ``LagrangesMethod``.
"""

from __future__ import annotations

import sympy as sp
from sympy.physics import mechanics as me

from nhham.system.mechanics import from_mechanics


def rolling_disc_3d(values=True):
    q1, q2, q3, x, y = me.dynamicsymbols("q1 q2 q3 x y")
    m, r, g = sp.symbols("m r g", positive=True)
    N = me.ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])        # yaw
    Lf = Y.orientnew("L", "Axis", [q2, Y.x])       # lean
    R = Lf.orientnew("R", "Axis", [q3, Lf.y])      # spin (disc plane normal = L.y)
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y)        # contact point (a point of the ground path)
    Dmc = C.locatenew("Dmc", r * Lf.z)             # disc centre
    Dmc.set_vel(N, Dmc.pos_from(O).dt(N))
    I = me.inertia(Lf, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4)
    disc = me.RigidBody("disc", Dmc, R, m, (I, Dmc))
    disc.potential_energy = m * g * Dmc.pos_from(O).dot(N.z)
    Lag = me.Lagrangian(N, disc)
    # Velocity of the disc's material point at the contact: v_Dmc + w x (C - Dmc).
    w = R.ang_vel_in(N)
    v_contact = Dmc.vel(N) + w.cross(C.pos_from(Dmc))
    nonhol = [v_contact.dot(N.x), v_contact.dot(N.y)]
    params = {"m": 1.0, "r": 0.5, "g": 9.81} if values else None
    system = from_mechanics(Lag, [q1, q2, q3, x, y], nonhol_coneqs=nonhol,
                            parameters=params, name="rolling disc in 3-D")
    return system, dict(L=Lag, q=[q1, q2, q3, x, y], nonhol=nonhol, frame=N)
