"""The gallery's headers against the command, line by line (issue 36's five scenes).

Each scene's header comment says, worked out by hand, what ``nhham classify`` reports
and the closed forms of its multiplier and motion. One test per scene checks every line
of its "What `nhham classify` should report" block against ``classify --json`` (the line
quoted in the assertion's message); one more checks the closed forms against
``derive --json`` at points of M_1 built here by hand (velocities solved from the
constraints), with the scene's parameter values read from its file. The expected values
come from the headers' formulas, evaluated here without nhham. DESIGN.md §2's signs:
m a = F - lambda dphi/dv, so the reaction's power is -lambda (dphi/dv . v) (the balance
nhham.numerics.model reports).

Not checked here: the values a simulation reaches (zeta(3) of the ball, the bead at
t = 2, s(t) and the isokinetic motion at t_end), which tests/cli/test_time_dependent_command.py,
tests/cli/test_chetaev_command.py and tests/numerics/test_*_runs.py check; here the
closed-form motions are checked pointwise against the derived field instead.
"""

import cmath
import json
import math
import tomllib

import sympy as sp

from nhham import parse_expression
from tests.cli.conftest import EXAMPLES, envelope_of, run_inprocess

TOL = 1e-9


def result_of(command, example):
    status, envelope, err = envelope_of(command, example)
    assert status == 0, err
    return envelope


def explicit_derive(example):
    """``derive --json --explicit``: the closed forms even where W is not diagonal and
    n > 3 (the spun-up ball's default is the implicit mass-matrix form)."""
    status, out, err = run_inprocess("derive", str(EXAMPLES / example), "--json", "--explicit")
    assert status == 0, err
    return json.loads(out)


def parameters(example):
    """The scene's parameter values, read from its file (its data, not nhham's answer)."""
    return tomllib.loads((EXAMPLES / example).read_text())["parameters"]


def at(envelope, expr, point):
    """``expr`` at ``point`` (names to numbers) and the scene's parameter values."""
    values = {**parameters(envelope["scene"]["path"].rsplit("/", 1)[-1]), **point}
    return float(expr.xreplace({sp.Symbol(k): sp.Float(v, 30) for k, v in values.items()}))


def value(envelope, text, point):
    """The command's expression ``text`` at ``point``."""
    return at(envelope, parse_expression(text, envelope["scene"]["names"]), point)


def close(got, expected):
    return abs(got - expected) <= TOL * max(1.0, abs(expected))


def energy_rate(envelope, point):
    """dE/dt along the derived field at ``point``: dE/dq . v + dE/dv . a + dE/dt."""
    names = envelope["scene"]["names"]
    r = envelope["result"]
    energy = parse_expression(r["energy"], names)
    rates = {name: value(envelope, f, point) for name, f in zip(r["state"], r["field"])}
    total = sum(at(envelope, sp.diff(energy, sp.Symbol(name)), point) * rate
                for name, rate in rates.items())
    if "t" in names:
        total += at(envelope, sp.diff(energy, sp.Symbol("t")), point)
    return total


def accelerations(envelope, point):
    r = envelope["result"]
    n = len(r["state"]) // 2
    return [value(envelope, f, point) for f in r["field"][n:]]


def single_time_independent_chetaev(r, line):
    assert r["constraint_kinds"] == [{"label": "constraints[0]", "kind": "nonlinear (Chetaev)",
                                      "time_dependent": False}], line
    assert "time" not in r, "no t in the scene: the verdict is not about an instant"


def not_applicable(r, line):
    assert r["integrable"] is None, line
    assert r["integrability"] == "not applicable for nonlinear constraints", line


def one_stage_determined(r, line):
    assert len(r["stages"]) == 1 and r["final_labels"] == r["stages"][0]["labels"], line
    assert r["status"] == "determined" and r["free_multipliers"] == 0, line


def at_a_generic_instant(envelope, line):
    r = envelope["result"]
    assert {"name": "t", "value": None} in envelope["scene"]["parameters"], line
    assert r["time"]["name"] == "t", line
    assert r["time"]["question"].startswith("generic instant"), line
    assert r["time"]["lagrangian"] is False, "L has no t"


# --- ball on a turntable spun up --------------------------------------------------------

BALL = "ball_on_turntable_spun_up.toml"


def ball_point(t, x, y, phi, theta, psi, phi_dot, theta_dot, psi_dot):
    """A point of M_1: x', y' solved from the scene's two constraints."""
    p = parameters(BALL)
    r, alpha = p["r"], p["alpha"]
    x_dot = r * (theta_dot * math.sin(phi) - psi_dot * math.sin(theta) * math.cos(phi)) \
        - alpha * t * y
    y_dot = -r * (theta_dot * math.cos(phi) + psi_dot * math.sin(theta) * math.sin(phi)) \
        + alpha * t * x
    return dict(t=t, x=x, y=y, phi=phi, theta=theta, psi=psi, x_dot=x_dot, y_dot=y_dot,
                phi_dot=phi_dot, theta_dot=theta_dot, psi_dot=psi_dot)


BALL_POINTS = [ball_point(0.8, 0.3, -1.1, 0.4, 1.2, 0.5, 0.3, -0.7, 0.9),
               ball_point(2.5, -0.6, 0.9, 2.1, 0.7, -1.3, -1.4, 0.6, 0.2)]


def test_ball_on_turntable_spun_up_classify_as_its_header_says():
    envelope = result_of("classify", BALL)
    r = envelope["result"]
    line = "the constraints are affine and time-dependent (h = alpha t (y, -x))"
    assert [c["kind"] for c in r["constraint_kinds"]] == ["affine", "affine"], line
    for text, h in zip(r["final_constraints"], ("alpha*t*y", "-alpha*t*x")):
        for p in BALL_POINTS:
            rest = {**p, "x_dot": 0, "y_dot": 0, "phi_dot": 0, "theta_dot": 0, "psi_dot": 0}
            assert close(value(envelope, text, rest), value(envelope, h, rest)), line
    line = "t a parameter without a value: the verdict holds at a generic instant"
    at_a_generic_instant(envelope, line)
    line = "regular: yes; C does not depend on h, so it is the rolling ball's: rank 2"
    assert r["regular"] is True and r["rank_c"] == 2, line
    line = "constraint algorithm: M_f = M_1 (one stage); status: determined; free multipliers: 0"
    one_stage_determined(r, line)
    assert r["free_multiplier_symbols"] == [], line
    line = "integrability: the linear part is the rolling ball's: not integrable"
    assert r["integrable"] is False, line
    line = "both constraints time-dependent"
    assert [c["time_dependent"] for c in r["constraint_kinds"]] == [True, True], line


def test_ball_on_turntable_spun_up_derive_against_the_header_closed_forms():
    envelope = explicit_derive(BALL)
    r = envelope["result"]
    p = parameters(BALL)
    m, rad, inertia, alpha = p["m"], p["r"], p["I"], p["alpha"]
    k = inertia / (inertia + m * rad**2)
    assert k == 2 / 7, "k = I/(I + m r^2) = 2/7"
    for point in BALL_POINTS:
        t = point["t"]
        # "C does not depend on h, so it is the rolling ball's": by hand, mu W^-1 mu^T =
        # (1/m + r^2/I) Id (the Euler-angle rows have length 1 in the sphere's metric)
        for i, row in enumerate(r["constraint_matrix"]):
            for j, entry in enumerate(row):
                expected = -(1 / m + rad**2 / inertia) if i == j else 0.0
                assert close(value(envelope, entry, point), expected), "C: rolling ball's"
        # "zeta'' = i k d/dt(Omega zeta) = i k alpha (zeta + t zeta')", Omega = alpha t
        zeta = complex(point["x"], point["y"])
        zeta_dot = complex(point["x_dot"], point["y_dot"])
        zeta_ddot = 1j * k * alpha * (zeta + t * zeta_dot)
        a = accelerations(envelope, point)
        assert close(a[0], zeta_ddot.real) and close(a[1], zeta_ddot.imag), "zeta''"
        # the reaction -mu^T lambda is the centre's only force: m zeta'' = -(lambda_1 +
        # i lambda_2); "dE/dt = lambda . h" with h = alpha t (y, -x)
        lam = [value(envelope, f, point) for f in r["multipliers"]]
        assert close(lam[0], -m * zeta_ddot.real) and close(lam[1], -m * zeta_ddot.imag)
        h = (alpha * t * point["y"], -alpha * t * point["x"])
        expected = -m * (zeta_ddot.real * h[0] + zeta_ddot.imag * h[1])
        assert close(energy_rate(envelope, point), expected), "dE/dt = lambda . h"
        assert abs(expected) > 0.1, "the motor works on the ball here"
    # "zeta(0) = 1, zeta'(0) = i (theta_dot = -1 solved from the constraints at t = 0)"
    start = ball_point(0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0)
    assert close(start["x_dot"], 0.0) and close(start["y_dot"], 1.0), "theta_dot = -1"
    assert cmath.isclose(complex(start["x_dot"], start["y_dot"]), 1j)


# --- bead on a turning wire -------------------------------------------------------------

BEAD = "bead_on_turning_wire.toml"


def bead_point(t, r, r_dot):
    """On the wire at distance r with radial speed r': v = r' e_r + r Omega e_theta."""
    omega = parameters(BEAD)["Omega"]
    c, s = math.cos(omega * t), math.sin(omega * t)
    return dict(t=t, x=r * c, y=r * s, x_dot=r_dot * c - r * omega * s,
                y_dot=r_dot * s + r * omega * c)


def bead_on_the_motion(t, r0=1.0):
    """r(t) = r0 cosh(Omega t) from rest on the wire."""
    omega = parameters(BEAD)["Omega"]
    return bead_point(t, r0 * math.cosh(omega * t), r0 * omega * math.sinh(omega * t))


def test_bead_on_turning_wire_classify_as_its_header_says():
    envelope = result_of("classify", BEAD)
    r = envelope["result"]
    line = "Its complete lift dg/dq v + dg/dt is the affine constraint phi = -sin(Omega t) x' " \
        "+ cos(Omega t) y' - Omega (x cos(Omega t) + y sin(Omega t))"
    assert [c["label"] for c in r["constraint_kinds"]] == ["holonomic[0]", "holonomic[0].lift"]
    assert [c["kind"] for c in r["constraint_kinds"]] == ["holonomic", "affine"], line
    omega = parameters(BEAD)["Omega"]
    for t, x, y, x_dot, y_dot in ((0.3, 0.7, -1.2, 0.4, 2.2), (1.9, -0.5, 0.8, -1.1, 0.6)):
        c, s = math.cos(omega * t), math.sin(omega * t)
        phi = -s * x_dot + c * y_dot - omega * (x * c + y * s)
        got = value(envelope, r["final_constraints"][1],
                    dict(t=t, x=x, y=y, x_dot=x_dot, y_dot=y_dot))
        assert close(got, phi), line
    line = "t a parameter without a value: the verdict holds at a generic instant"
    at_a_generic_instant(envelope, line)
    line = "regular: yes (C = -1/m)"  # C's value: the derive test
    assert r["regular"] is True and r["rank_c"] == 1, line
    line = "constraint algorithm: M_f = M_1 (one stage); determined"
    one_stage_determined(r, line)
    line = "integrable: yes (holonomic)"
    assert r["integrable"] is True, line
    line = "the constraint is time-dependent"
    assert [c["time_dependent"] for c in r["constraint_kinds"]] == [True, True], line


def test_bead_on_turning_wire_derive_against_the_header_closed_forms():
    envelope = result_of("derive", BEAD)
    r = envelope["result"]
    p = parameters(BEAD)
    m, omega = p["m"], p["Omega"]
    points = [(0.7, 1.3, -0.4), (1.6, 0.6, 2.3)]
    points += [(t, math.cosh(omega * t), omega * math.sinh(omega * t)) for t in (0.5, 2.0)]
    for t, rad, r_dot in points:
        point = bead_point(t, rad, r_dot)
        e_theta = (-math.sin(omega * t), math.cos(omega * t))
        assert close(value(envelope, r["constraint_matrix"][0][0], point), -1 / m), "C = -1/m"
        # "r'' = Omega^2 r": the acceleration (r'' - r Omega^2) e_r + 2 r' Omega e_theta is
        # the Coriolis term alone, "N = 2 m Omega r'" along e_theta
        a = accelerations(envelope, point)
        normal = 2 * m * omega * r_dot
        assert close(a[0], normal / m * e_theta[0]) and close(a[1], normal / m * e_theta[1])
        # "nhham's reaction -mu^T lambda with mu = (-sin(Omega t), cos(Omega t)) gives
        # lambda = -N"
        lam = value(envelope, r["multipliers"][0], point)
        assert close(lam, -normal), "lambda = -N"
        # "The energy m r'^2/2 + m Omega^2 r^2/2 grows: the motor's power is N Omega r =
        # lambda . h (h = -Omega r)"
        assert close(value(envelope, r["energy"], point),
                     m * r_dot**2 / 2 + m * omega**2 * rad**2 / 2), "E"
        assert close(energy_rate(envelope, point), normal * omega * rad), "N Omega r"
        assert close(normal * omega * rad, lam * (-omega * rad)), "= lambda . h"
    # "lambda = -N = -2 m Omega^2 r0 sinh(Omega t)" on the motion from rest, r0 = 1
    for t in (0.5, 2.0):
        lam = value(envelope, r["multipliers"][0], bead_on_the_motion(t))
        assert close(lam, -2 * m * omega**2 * math.sinh(omega * t)), "lambda on the motion"


# --- Appell-Hamel -----------------------------------------------------------------------

APPELL = "appell_hamel.toml"


def appell_point(x_dot, y_dot):
    a = parameters(APPELL)["a"]
    return dict(x=0.4, y=-1.3, z=2.2, x_dot=x_dot, y_dot=y_dot,
                z_dot=a * math.hypot(x_dot, y_dot))


def test_appell_hamel_classify_as_its_header_says():
    r = result_of("classify", APPELL)["result"]
    line = "constraints[0]: nonlinear (Chetaev); C = -(1 + a^2)/m, rank 1: C regular on M_1"
    single_time_independent_chetaev(r, line)
    assert r["rank_c"] == 1 and r["regular"] is True, line  # C's value: the derive test
    line = "multiplier: lambda = m g/(1 + a^2) (constant)"  # its value: the derive test
    one_stage_determined(r, line)
    assert r["free_multiplier_symbols"] == [], line
    line = "integrability: not applicable (nonlinear constraint)"
    not_applicable(r, line)


def test_appell_hamel_derive_against_the_header_closed_forms():
    envelope = result_of("derive", APPELL)
    r = envelope["result"]
    p = parameters(APPELL)
    m, g, a = p["m"], p["g"], p["a"]
    lam = m * g / (1 + a**2)
    for point in (appell_point(3.0, 4.0), appell_point(-1.2, 0.7)):
        s = math.hypot(point["x_dot"], point["y_dot"])
        line = "C = -(1 + a^2)/m"
        assert close(value(envelope, r["constraint_matrix"][0][0], point), -(1 + a**2) / m), line
        line = "multiplier: lambda = m g/(1 + a^2) (constant)"
        assert close(value(envelope, r["multipliers"][0], point), lam), line
        x_ddot, y_ddot, z_ddot = accelerations(envelope, point)
        line = "x'' = -(lambda a/m) x'/s, so the horizontal direction is fixed"
        assert close(x_ddot, -lam * a / m * point["x_dot"] / s), line
        assert close(y_ddot, -lam * a / m * point["y_dot"] / s), line
        line = "s(t) = s0 - a g t/(1 + a^2)"
        s_dot = (point["x_dot"] * x_ddot + point["y_dot"] * y_ddot) / s
        assert close(s_dot, -a * g / (1 + a**2)), line
        line = "z'' = -a^2 g/(1 + a^2)"
        assert close(z_ddot, -a**2 * g / (1 + a**2)), line
        line = "energy conserved (phi homogeneous of degree 1 in v)"
        assert close(energy_rate(envelope, point), 0.0), line


# --- isokinetic particle ----------------------------------------------------------------

ISOKINETIC = "isokinetic_particle.toml"


def isokinetic_motion(t):
    """The header's motion from the origin with velocity (c, 0): u = g t/c."""
    p = parameters(ISOKINETIC)
    g, c = p["g"], p["c"]
    u = g * t / c
    gd = 2 * math.atan(math.tanh(u / 2))
    return dict(x=c**2 / g * gd, y=-(c**2) / g * math.log(math.cosh(u)),
                x_dot=c / math.cosh(u), y_dot=-c * math.tanh(u))


def test_isokinetic_particle_classify_as_its_header_says():
    r = result_of("classify", ISOKINETIC)["result"]
    line = "constraints[0]: nonlinear (Chetaev); C = -c^2/m on M_1: C regular on M_1"
    single_time_independent_chetaev(r, line)
    assert r["rank_c"] == 1 and r["regular"] is True, line  # C's value: the derive test
    line = "multiplier: lambda = -m g y'/c^2"  # its value: the derive test
    one_stage_determined(r, line)
    assert r["free_multiplier_symbols"] == [], line
    line = "integrability: not applicable (nonlinear constraint)"
    not_applicable(r, line)


def test_isokinetic_particle_derive_against_the_header_closed_forms():
    envelope = result_of("derive", ISOKINETIC)
    r = envelope["result"]
    p = parameters(ISOKINETIC)
    m, g, c = p["m"], p["g"], p["c"]
    on_m1 = [dict(x=0.5, y=-0.2, x_dot=c * math.cos(b), y_dot=c * math.sin(b))
             for b in (0.4, 2.9)]
    for point in on_m1 + [isokinetic_motion(0.3), isokinetic_motion(1.0)]:
        line = "C = -c^2/m on M_1"
        assert close(value(envelope, r["constraint_matrix"][0][0], point), -(c**2) / m), line
        line = "multiplier: lambda = -m g y'/c^2"
        lam = value(envelope, r["multipliers"][0], point)
        assert close(lam, -m * g * point["y_dot"] / c**2), line
        x_ddot, y_ddot = accelerations(envelope, point)
        line = "the kinetic energy m c^2/2 stays constant"
        assert close(m * (point["x_dot"] * x_ddot + point["y_dot"] * y_ddot), 0.0), line
        line = "the reaction's power is -lambda (d phi/d v) v = -lambda c^2"
        assert close(energy_rate(envelope, point), -lam * c**2), line
    for t in (0.3, 1.0):
        u = g * t / c
        point = isokinetic_motion(t)
        # "x = (c^2/g) gd(u), y = -(c^2/g) ln cosh(u)" has "x' = c sech(u), y' = -c tanh(u)"
        # (central differences of the header's positions), and the velocities' derivatives
        # by hand, -g sech(u) tanh(u) and -g sech(u)^2, are the derived field
        step = 1e-5
        ahead, behind = isokinetic_motion(t + step), isokinetic_motion(t - step)
        for q in ("x", "y"):
            assert abs((ahead[q] - behind[q]) / (2 * step) - point[f"{q}_dot"]) < 1e-8, q
        x_ddot, y_ddot = accelerations(envelope, point)
        line = "x' = c sech(u), y' = -c tanh(u)"
        assert close(x_ddot, -g * math.tanh(u) / math.cosh(u)), line
        assert close(y_ddot, -g / math.cosh(u) ** 2), line
        line = "the reaction's power is ... = -m g c tanh(u) = m g y'"
        assert close(energy_rate(envelope, point), -m * g * c * math.tanh(u)), line


# --- perpendicular velocities -----------------------------------------------------------

PERPENDICULAR = "perpendicular_velocities.toml"
# two pairs of perpendicular velocities (points of M_1), away from rest
PERPENDICULAR_POINTS = [
    dict(x1=0.2, y1=-0.7, x2=1.3, y2=-0.4, x1_dot=1.0, y1_dot=0.5, x2_dot=-0.4, y2_dot=0.8),
    dict(x1=-1.0, y1=0.3, x2=-0.6, y2=2.1, x1_dot=-0.3, y1_dot=1.1, x2_dot=2.2, y2_dot=0.6),
]


def test_perpendicular_velocities_classify_as_its_header_says():
    envelope = result_of("classify", PERPENDICULAR)
    r = envelope["result"]
    line = "constraints[0]: nonlinear (Chetaev); C = -(|v2|^2/m1 + |v1|^2/m2): C regular on M_1"
    single_time_independent_chetaev(r, line)
    assert r["regular"] is True, line  # C's value: the derive test
    line = "(rank 1 away from rest)"
    assert r["rank_c"] == 1, line
    line = "d phi/d v = (x2', y2', x1', y1') vanishes only where both particles are at rest " \
        "(points of M_1, not all of it)"
    assert any("drops from 1 to 0" in w for w in envelope["warnings"]), line
    line = "multiplier: lambda = (F1.v2/m1 + F2.v1/m2)/(|v2|^2/m1 + |v1|^2/m2)"
    one_stage_determined(r, line)
    assert r["free_multiplier_symbols"] == [], line
    line = "integrability: not applicable (nonlinear constraint)"
    not_applicable(r, line)


def test_perpendicular_velocities_derive_against_the_header_closed_forms():
    envelope = result_of("derive", PERPENDICULAR)
    r = envelope["result"]
    p = parameters(PERPENDICULAR)
    m1, m2, g, k = p["m1"], p["m2"], p["g"], p["k"]
    for point in PERPENDICULAR_POINTS:
        v1 = (point["x1_dot"], point["y1_dot"])
        v2 = (point["x2_dot"], point["y2_dot"])
        assert v1[0] * v2[0] + v1[1] * v2[1] == 0, "a point of M_1"
        f1 = (0.0, -m1 * g)
        f2 = (-k * point["x2"], -k * point["y2"])

        def dot(u, w):
            return u[0] * w[0] + u[1] * w[1]

        line = "C = -(|v2|^2/m1 + |v1|^2/m2)"
        c = -(dot(v2, v2) / m1 + dot(v1, v1) / m2)
        assert close(value(envelope, r["constraint_matrix"][0][0], point), c), line
        line = "lambda = (F1.v2/m1 + F2.v1/m2)/(|v2|^2/m1 + |v1|^2/m2)"
        lam = (dot(f1, v2) / m1 + dot(f2, v1) / m2) / -c
        assert close(value(envelope, r["multipliers"][0], point), lam), line
        line = "m_k a_k = F_k - lambda d phi/d v_k, d phi/d v = (x2', y2', x1', y1')"
        expected = [(f1[0] - lam * v2[0]) / m1, (f1[1] - lam * v2[1]) / m1,
                    (f2[0] - lam * v1[0]) / m2, (f2[1] - lam * v1[1]) / m2]
        for got, want in zip(accelerations(envelope, point), expected):
            assert close(got, want), line
        line = "Energy conserved (phi homogeneous of degree 2 in v)"
        assert close(energy_rate(envelope, point), 0.0), line
