"""Contact forces from the multipliers (nhham.numerics.contact_forces).

A rolling disc in 3-D with its contact height as a holonomic constraint (so that all
three components of the contact force are constraint forces), written by hand in
examples/make_disc_on_ground.py: yaw theta about N.z, lean phi about the heading A.x,
spin psi about the axle B.y; the centre (x, y, z); the contact point P = C - r B.z. The static case is checked against m g by
hand, the moving one against Newton's law for the centre of mass, which does not come
from the multipliers: f_P - m g e_z = m a_C.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import nhham
from nhham.numerics.codegen import numeric_model
from nhham.numerics.contact_forces import contact_forces
from nhham.system.contacts import ContactPoint

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
from make_disc_on_ground import VALUES, disc  # noqa: E402

M, G, R = VALUES["m"], VALUES["g"], VALUES["r"]


@pytest.fixture(scope="module")
def rolling_disc():
    system, contact = disc()
    return system, contact, numeric_model(system, backend="numpy")


def _state(system, q, free):
    """(q, v) on M_1: theta_dot, phi_dot, psi_dot given, x_dot, y_dot, z_dot solved."""
    subs = dict(zip(system.coordinates, q))
    subs.update({p: v for p, v in system.parameter_values.items()})
    vels = system.velocities
    given = dict(zip(vels[3:], free))
    rows = [sp.expand(c.xreplace(subs).xreplace(given)) for c in system.phi]
    sol = sp.solve(rows, vels[:3], dict=True)[0]
    v = [float(sol[s]) for s in vels[:3]] + list(free)
    return np.array(list(q) + v, dtype=float)


def test_a_disc_standing_still_is_held_up_by_m_g(rolling_disc):
    """Upright at rest (an equilibrium): the ground pushes up with m g, nothing else."""
    system, contact, model = rolling_disc
    y = _state(system, [0.3, -0.2, R, 0.7, 0.0, 1.1], [0.0, 0.0, 0.0])
    lam = model.multipliers(y)
    out = contact_forces(system, [contact], y, lam)
    assert np.allclose(out.forces["ground"][0], [0.0, 0.0, M * G], atol=1e-12)
    assert out.residuals["ground"][0] < 1e-12 and out.rank["ground"] == 3
    assert out.warnings == ()


def test_the_contact_force_of_a_rolling_disc_obeys_newton_for_the_centre(rolling_disc):
    """Leaning, turning and spinning at random states of M_1: f_P - m g e_z = m a_C
    with a_C the centre's acceleration from the projected field."""
    system, contact, model = rolling_disc
    rng = np.random.default_rng(4)
    states = []
    for _ in range(5):
        phi = rng.uniform(-0.6, 0.6)
        q = [rng.normal(), rng.normal(), R * np.cos(phi), rng.uniform(-3, 3), phi,
             rng.uniform(-3, 3)]
        states.append(_state(system, q, rng.normal(size=3) * 2))
    Y = np.array(states)
    lam = np.array([model.multipliers(y) for y in Y])
    out = contact_forces(system, [contact], Y, lam)
    for y, f in zip(Y, out.forces["ground"]):
        a = model.rhs(0.0, y)[6:9]  # x'', y'', z''
        assert np.allclose(f - [0.0, 0.0, M * G], M * a, rtol=1e-9, atol=1e-9)
    assert out.residuals["ground"].max() < 1e-10


def test_constraints_that_are_not_the_points_are_reported(rolling_disc):
    """The lateral constraint alone attached to the centre of the disc (whose velocity is
    not constrained that way): the residual is large and a warning says so."""
    system, contact, model = rolling_disc
    y = _state(system, [0.0, 0.0, R * np.cos(0.3), 0.5, 0.3, 0.0], [0.4, -0.2, 3.0])
    centre = ContactPoint("centre", tuple(sp.symbols("x_dot y_dot z_dot")),
                          ("constraints[1]",))
    out = contact_forces(system, [centre], y, model.multipliers(y))
    assert out.residuals["centre"][0] > 1e-3
    assert "not velocity conditions of the point" in out.warnings[0]


def test_the_bicycle_at_rest_carries_its_front_load_by_hand():
    """The benchmark bicycle upright at rest: the front contact force is vertical and
    equals g (m_frame x_frame + m_fork x_fork + m_wf w) / w with the benchmark's
    wheelbase w = 1.02 m and centres of mass at x = 0.3 (frame, 85 kg), 0.9 (fork,
    4 kg), w (front wheel, 3 kg) (Meijaard et al. 2007, table 1); the rear contact's
    height is built into the coordinates, so only its horizontal force is a constraint
    force (rank 2, said in a warning)."""
    from nhham.system.scene import load_scene

    scene = load_scene(Path(__file__).parents[2] / "examples" / "whipple_bicycle.toml")
    system = scene.system
    model = numeric_model(system, backend="numpy")
    y = np.zeros(2 * system.n)
    out = contact_forces(system, scene.contacts, y, model.multipliers(y))
    w, g = 1.02, 9.81
    front = g * (85.0 * 0.3 + 4.0 * 0.9 + 3.0 * w) / w
    assert np.allclose(out.forces["front"][0], [0.0, 0.0, front], rtol=1e-9, atol=1e-9)
    assert np.allclose(out.forces["rear"][0], 0.0, atol=1e-9)
    assert out.rank == {"rear": 2, "front": 3}
    assert any("rear" in w and "rank 2" in w for w in out.warnings)


def test_simulate_keeps_the_contact_forces_with_the_trajectory(rolling_disc):
    """simulate(..., contacts=) puts the forces at the stored states on the result, the
    same as contact_forces on its states and multipliers; a NumericModel is refused (the
    velocity maps are the System's)."""
    system, contact, model = rolling_disc
    y0 = _state(system, [0.0, 0.0, R * np.cos(0.2), 0.0, 0.2, 0.0], [1.0, 0.0, -8.0])
    res = nhham.simulate(system, (0.0, 0.3), y0, rtol=1e-10, contacts=(contact,), warn=False)
    got = res.contact_forces.forces["ground"]
    assert got.shape == (len(res.t), 3)
    direct = contact_forces(system, [contact], res.states, res.multipliers.T)
    assert np.array_equal(got, direct.forces["ground"])
    assert nhham.simulate(system, (0.0, 0.1), y0, warn=False).contact_forces is None
    with pytest.raises(nhham.InputError, match="contacts need the System"):
        nhham.simulate(model, (0.0, 0.1), y0, contacts=(contact,))


def test_the_sleighs_blade_with_a_plain_zero_height():
    """The Chaplygin sleigh at theta = 0 with x' = 1, theta' = 1 (y' = a theta' = 0.5):
    by hand w' = -m a u w / (I + m a^2) = -1 and y'' = u w + a w' = 0.5, so the blade
    pushes m y'' = 0.5 across itself; its height, a plain 0, is a constant expression."""
    sleigh = nhham.models.chaplygin_sleigh()
    theta, (xd, yd, thd), a = sleigh.coordinates[2], sleigh.velocities, sp.Symbol("a")
    blade = ContactPoint("blade", (xd + a * sp.sin(theta) * thd, yd - a * sp.cos(theta) * thd,
                                   0), ("constraints[0]",))
    assert blade.velocity[2] == 0 and isinstance(blade.velocity[2], sp.Integer)
    model = numeric_model(sleigh, backend="numpy")
    y = model.state(dict(x=0.0, y=0.0, theta=0.0, x_dot=1.0, y_dot=0.5, theta_dot=1.0))
    out = contact_forces(sleigh, [blade], y, model.multipliers(y))
    assert np.allclose(out.forces["blade"][0], [0.0, 0.5, 0.0], atol=1e-12)
    assert out.rank["blade"] == 2
