"""An independent route to the rattleback's spin stability: sympy's KanesMethod in
body-frame speeds (tests only).

The body of examples/make_rattleback.py (ellipsoidal bottom x^2/a^2 + y^2/b^2 + z^2/c^2
= 1, mass centre at height h above its lowest point, central inertia with the product
I12), written as Kane & Levinson write a rolling body: generalized speeds u1, u2, u3 the
body-frame components of omega, the mass centre's velocity omega x (G - P) (the contact
point P at rest), gravity on G. The equations of u1..u3 and of the angles' rates do not
depend on yaw, x, y: the reduced state z = (roll, pitch, u1, u2, u3) has the equilibrium
(0, 0, 0, 0, w) for every spin w, and the Jacobian of z' = f(z) there (complex step,
exact to rounding) is the reduced linearisation; its eigenvalue 0 (the u3 direction: the
neighbouring spins) aside, its spectrum is that of the relative equilibrium modulo the
rotation and the translations. Nothing here comes from nhham.
"""

import functools

import numpy as np
import sympy as sp
from sympy.physics import mechanics as me


@functools.lru_cache(maxsize=None)
def reduced_field(values: tuple):
    """z' = f(z) of the reduced state z = (roll, pitch, u1, u2, u3), numpy (complex ok)."""
    p = dict(values)
    yaw, roll, pitch, x, y = me.dynamicsymbols("yaw roll pitch x y")
    u1, u2, u3, u4, u5 = me.dynamicsymbols("u1:6")
    m, g, a, b, c, h, I11, I22, I33, I12 = sp.symbols("m g a b c h I11 I22 I33 I12")
    t = me.dynamicsymbols._t
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Body", [yaw, roll, pitch], "ZXY")
    w_BN = B.ang_vel_in(N)
    B.set_ang_vel(N, u1 * B.x + u2 * B.y + u3 * B.z)
    n1, n2, n3 = N.z.dot(B.x), N.z.dot(B.y), N.z.dot(B.z)
    s = sp.sqrt(a ** 2 * n1 ** 2 + b ** 2 * n2 ** 2 + c ** 2 * n3 ** 2)
    r_PG = (a ** 2 * n1 * B.x + b ** 2 * n2 * B.y + c ** 2 * n3 * B.z) / s + (h - c) * B.z
    O = me.Point("O")
    O.set_vel(N, 0)
    G = O.locatenew("G", x * N.x + y * N.y)
    G.set_vel(N, B.ang_vel_in(N).cross(r_PG))   # rolling: the contact point at rest
    body = me.RigidBody("body", G, B, m, (me.inertia(B, I11, I22, I33, I12, 0, 0), G))
    # the angles' rates solved by hand-sized algebra (omega = A(q) q'), so that the
    # kinematic equations are explicit (sympy's own solve leaves 1/sin(pitch) terms)
    angles = [yaw.diff(t), roll.diff(t), pitch.diff(t)]
    A = sp.Matrix([[w_BN.dot(e).diff(r) for r in angles] for e in (B.x, B.y, B.z)])
    rates = A.adjugate() * sp.Matrix([u1, u2, u3]) / sp.trigsimp(A.det())
    kd = [angles[i] - rates[i] for i in range(3)] + [x.diff(t) - u4, y.diff(t) - u5]
    vc = [u4 - G.vel(N).dot(N.x), u5 - G.vel(N).dot(N.y)]
    kane = me.KanesMethod(N, q_ind=[yaw, roll, pitch, x, y], u_ind=[u1, u2, u3],
                          u_dependent=[u4, u5], kd_eqs=kd, velocity_constraints=vc)
    kane.kanes_equations([body], [(G, -m * g * N.z)])
    M, F = kane.mass_matrix, kane.forcing
    rates = kane.kindiffdict()
    # the yaw enters the expressions through cos^2 + sin^2 only: it is an argument here,
    # and the tests evaluate at two yaws
    z = [roll, pitch, u1, u2, u3, yaw]
    zs = sp.symbols("z0:6")
    plain = dict(zip(z, zs))
    point = {sp.Symbol(k): v for k, v in p.items()}
    exprs = [rates[roll.diff(t)], rates[pitch.diff(t)]]
    sub = lambda e: me.msubs(e, plain).xreplace(point)   # noqa: E731
    pieces = [sub(M), sub(F), sp.Matrix([sub(e) for e in exprs])]
    left = set().union(*(me.find_dynamicsymbols(e) for e in pieces))
    assert not left, f"the reduced equations depend on {left}"
    fM, fF, fk = (sp.lambdify([zs], e, "numpy") for e in pieces)

    def field(zv):
        du = np.linalg.solve(np.array(fM(zv), dtype=complex),
                             np.array(fF(zv), dtype=complex).ravel())
        # M, F cover u1..u5 (the constraints' rows for u4, u5): u1..u3 are the first
        return np.concatenate([np.array(fk(zv), dtype=complex).ravel(), du[:3]])

    return field


def reduced_jacobian(values: dict, spin: float, yaw: float = 0.0,
                     h: float = 1e-30) -> np.ndarray:
    """The complex-step Jacobian of the reduced field at (0, 0, 0, 0, spin) (at the
    given yaw, which it does not depend on)."""
    f = reduced_field(tuple(sorted(values.items())))
    z0 = np.array([0.0, 0.0, 0.0, 0.0, spin, yaw], dtype=complex)
    assert np.abs(f(z0)).max() < 1e-12, "not an equilibrium of the reduced field"
    return np.column_stack([f(z0 + 1j * h * e).imag / h for e in np.eye(6)[:5]])
