"""The bicycle against the nonlinear benchmark of Basu-Mandal, Chatterjee & Papadopoulos
(2007, Proc. R. Soc. A 463, 1983-2003, "Hands-free circular motions of a benchmark
bicycle"), Table 1: a state of the benchmark bicycle leaning 35.6 degrees and its second
derivatives to 13 digits, from two independent formulations.

Their coordinates (the same map as the published conversions of J. K. Moore's
DynamicistToolKit): rear wheel centre (x, y, z) with z up, yaw theta, lean psi (pi/2
upright), pitch phi (pi upright), steer psi_f, wheel angles beta_r, beta_f, in axes
X = N.x, Y = -N.y, Z = N.z of nhham's scene (examples/make_whipple_bicycle.py: N.z up,
yaw about N.z, lean about the heading, the frame pitched by htangle + pitch about R.y,
steer about the head tube). Worked out from the frames:

    psi = theta,  phi = pi/2 - psi_b,  pitch = phi_b - pi,  delta = -psi_f,
    thetaR = beta_r,  thetaF = beta_f,
    x = -rR sin(theta) cos(psi_b) - x_b,  y = rR cos(theta) cos(psi_b) - y_b,

and the rates and accelerations by differentiating these. The state satisfies the
scene's constraints to the table's rounding; the accelerations match to 2e-12.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
import sympy.physics.mechanics as me

from nhham.numerics.codegen import numeric_model
from nhham.numerics.contact_forces import contact_forces
from nhham.system.scene import load_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
RR = 0.3

# Table 1: inputs (coordinates and speeds) and outputs (second derivatives).
STATE = dict(x=0.0, y=0.0, z=0.2440472102925, theta=0.0, psi=0.9501292851472,
             phi=3.1257073014894, psif=0.2311385135743, betar=0.0, betaf=0.0,
             xd=-2.8069345714545, yd=-0.1480982396001, zd=0.1058778746261,
             thetad=0.7830033527065, psid=0.6068425835418, phid=-0.0119185528069,
             psifd=0.4859824687093, betard=8.9129896614890, betafd=8.0133620584155)
ACCELERATIONS = dict(xdd=-0.5041626315047, ydd=-0.3449706619454, zdd=-1.4604528332980,
                     thetadd=0.8353281706379, psidd=-7.8555281128244,
                     phidd=0.1205543897884, psifdd=-4.6198904039403,
                     betardd=1.8472554144217, betafdd=2.4548072904550)


def to_scene(b: dict) -> dict:
    """Coordinates and rates of the scene from the Basu-Mandal state."""
    th, ps, thd, psd = b["theta"], b["psi"], b["thetad"], b["psid"]
    s1, c1, s2, c2 = math.sin(th), math.cos(th), math.sin(ps), math.cos(ps)
    q = dict(x=-RR * s1 * c2 - b["x"], y=RR * c1 * c2 - b["y"], psi=th, phi=math.pi / 2 - ps,
             pitch=b["phi"] - math.pi, thetaR=b["betar"], delta=-b["psif"],
             thetaF=b["betaf"])
    rates = dict(x=-RR * (c1 * thd * c2 - s1 * s2 * psd) - b["xd"],
                 y=RR * (-s1 * thd * c2 - c1 * s2 * psd) - b["yd"], psi=thd, phi=-psd,
                 pitch=b["phid"], thetaR=b["betard"], delta=-b["psifd"], thetaF=b["betafd"])
    return q, rates


def to_basu(b: dict, a: dict) -> dict:
    """The Basu-Mandal second derivatives from the scene's accelerations ``a`` at the
    state ``b``: the map above differentiated twice."""
    th, ps, thd, psd = b["theta"], b["psi"], b["thetad"], b["psid"]
    s1, c1, s2, c2 = math.sin(th), math.cos(th), math.sin(ps), math.cos(ps)
    out = dict(thetadd=a["psi"], psidd=-a["phi"], phidd=a["pitch"], psifdd=-a["delta"],
               betardd=a["thetaR"], betafdd=a["thetaF"])
    thdd, psdd = out["thetadd"], out["psidd"]
    # d2/dt2 of sin(th) cos(ps) and cos(th) cos(ps)
    sc = (-s1 * thd**2 * c2 + c1 * thdd * c2 - 2 * c1 * thd * s2 * psd
          - s1 * (c2 * psd**2 + s2 * psdd))
    cc = (-c1 * thd**2 * c2 - s1 * thdd * c2 + 2 * s1 * thd * s2 * psd
          - c1 * (c2 * psd**2 + s2 * psdd))
    out["xdd"] = -RR * sc - a["x"]
    out["ydd"] = RR * cc - a["y"]
    out["zdd"] = RR * (c2 * psdd - s2 * psd**2)
    return out


@pytest.fixture(scope="module")
def bicycle():
    scene = load_scene(EXAMPLES / "whipple_bicycle.toml")
    system = scene.system
    q, rates = to_scene(STATE)
    names = [c.name for c in system.coordinates]
    y = np.array([q[n] for n in names] + [rates[n] for n in names])
    model = numeric_model(system, backend="numpy")
    return scene, y, model


def test_the_state_is_on_M1(bicycle):
    """The converted Table 1 state satisfies the contact and rolling constraints to the
    table's rounding (13 digits): the conversion is right."""
    scene, y, _ = bicycle
    system = scene.system
    env = dict(zip((*system.coordinates, *system.velocities), y))
    env.update(system.parameter_values)
    residuals = [float(sp.sympify(e).xreplace(env)) for e in (*system.holonomic, *system.phi)]
    assert max(abs(r) for r in residuals) < 1e-12


def test_the_accelerations_match_table_1(bicycle):
    """Every second derivative of Table 1 to 1e-11 relative (found: 2e-12 at worst)."""
    scene, y, model = bicycle
    n = scene.system.n
    a = dict(zip([c.name for c in scene.system.coordinates], model.rhs(0.0, y)[n:]))
    got = to_basu(STATE, a)
    for key, expected in ACCELERATIONS.items():
        assert got[key] == pytest.approx(expected, rel=1e-11, abs=0), key


def test_the_contact_forces_balance_the_bicycle(bicycle):
    """At the Table 1 state, the contact forces from the multipliers with gravity give
    the rate of change of the whole bicycle's linear and angular momentum (about the
    origin), computed from the bodies of the sympy.physics.mechanics model and the
    accelerations: a check that does not come from the multipliers. The rear wheel's
    normal force is no constraint force (its height is built into the coordinates): it
    is taken from the vertical balance, and the other five equations checked."""
    scene, y, model = bicycle
    system = scene.system
    n = system.n
    forces = contact_forces(system, scene.contacts, y, model.multipliers(y))
    sys.path.insert(0, str(EXAMPLES))
    import make_whipple_bicycle as make

    msys, points = make.mechanics_model()
    N, O = msys.frame, msys.fixed_point
    t = me.dynamicsymbols._t
    q = list(msys.q)
    accelerations = model.rhs(0.0, y)[n:]
    values = {}
    for i, qi in enumerate(q):
        values[qi.diff(t, 2)] = accelerations[i]
    for i, qi in enumerate(q):
        values[qi.diff(t)] = y[n + i]
    for i, qi in enumerate(q):
        values[qi] = y[i]
    params = {sp.Symbol(k): v for k, v in make.benchmark_parameters().items()}

    def number(vector):
        m = vector.to_matrix(N)
        for group in (list(values)[:n], list(values)[n:2 * n], list(values)[2 * n:]):
            m = m.xreplace({k: values[k] for k in group})
        return np.array(m.xreplace(params).evalf(), dtype=float).ravel()

    g = make.benchmark_parameters()["g"]
    momentum, spin, weight, weight_moment = (me.Vector(0),) * 4
    for body in msys.bodies:
        r = body.masscenter.pos_from(O)
        a = r.dt(N).dt(N)
        momentum += body.mass * a
        spin += me.cross(r, body.mass * a) + (body.central_inertia
                                               & body.frame.ang_vel_in(N)).dt(N)
        weight += -body.mass * g * N.z
        weight_moment += me.cross(r, -body.mass * g * N.z)
    dP, dH = number(momentum), number(spin)
    W, MW = number(weight), number(weight_moment)
    where = {name: number(point.pos_from(O)) for name, _, _, point in points}
    f = {name: forces.forces[name][0].copy() for name in forces.points}
    f["rear"][2] = dP[2] - W[2] - f["front"][2]  # the rear normal force, by balance
    total = f["rear"] + f["front"] + W
    moment = sum(np.cross(where[k], f[k]) for k in f) + MW
    scale = np.linalg.norm(W)  # the weight, N; moments over the bicycle's metre, N m
    assert np.allclose(total, dP, rtol=0, atol=1e-10 * scale)  # found: 2e-16 relative
    assert np.allclose(moment, dH, rtol=0, atol=1e-10 * scale)
    assert f["rear"][2] > 0 and f["front"][2] > 0  # both wheels pushed up
