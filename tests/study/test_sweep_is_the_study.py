"""``nhham linearize --sweep`` and ``nhham sweep --what linearize`` answer alike on every
scene with a ``[steady]`` table (issue 43, item 3): the same verdict at every grid value,
the same eigenvalues, the same crossings (value to 1e-9, kind, direction) and the same
intervals left unlocated. Both take one reference (the first, middle and last values)
and their spectra from one batch implementation
(:func:`nhham.journeys.steady.sweep_reference`, :func:`~nhham.journeys.steady.steady_batch`);
this test keeps it so.

The scenes cover a touching eigenvalue and a crossing in one grid interval (the forced
sleigh, where before the command found U* and the study a crossing at 5.6e-31 and none
at U*; the sleigh with drag, its touch at a grid value), pairs colliding on the real axis
(the bicycles' weave), forces (the sleighs), control laws (the held pendulum, the
steered bicycle, the roller racer, the motor-driven robot), symmetries (the rattleback,
the trailer robot, the Mexican hat) and a cluster at 0 (the hoop). The forced sleigh's
crossing is checked against its closed form U* = -c / (m a) as well (its scene's header).
"""

from pathlib import Path

import numpy as np
import pytest

from nhham import load_scene
from nhham.journeys import linearize
from nhham.journeys.stability import sweep_scene, symmetry_generator
from nhham.numerics.codegen import numeric_model
from nhham.study.sweep import sweep

ROOT = Path(__file__).resolve().parents[2]

#: Every scene file with a [steady] table: the parameter swept and its grid (few values).
SWEEPS = {
    "examples/bicycle_steer_control.toml": ("v", "1:9:5"),
    "examples/differential_drive.toml": ("w", "-5:5:5"),
    "examples/differential_drive_motors.toml": ("tau", "-0.02:0.02:5"),
    "examples/rattleback.toml": ("w", "-30:30:5"),
    "examples/roller_racer.toml": ("U", "-1:2:4"),
    "examples/rolling_disc_3d.toml": ("w", "0:8:5"),
    "examples/suslov.toml": ("I13", "0:1:3"),
    "examples/whipple_bicycle.toml": ("v", "0:10:6"),
    "examples/whipple_bicycle_benchmark.toml": ("v", "0:10:6"),
    "tests/study/scenes/held_pendulum.toml": ("k", "-2:2:5"),
    "tests/study/scenes/pendulum_steady.toml": ("L2", "0.5:2:4"),
    "tests/study/scenes/sleigh_drag.toml": ("U", "-1:2:4"),
    "tests/study/scenes/two_parameter_spring.toml": ("p1", "-1:1:5"),
    "tests/study/scenes/wheel_spring.toml": ("p", "-1:1:5"),
    "tests/study/scenes/trailer_robot.toml": ("w", "-5:5:5"),
    "tests/study/scenes/forced_sleigh.toml": ("U", "-1.45:1.55:7"),
    "tests/study/scenes/upright_hoop.toml": ("w", "0:4:5"),
    "tests/study/scenes/mexican_hat.toml": ("a", "0:1:3"),
}


def test_every_scene_with_a_steady_table_is_compared():
    # a singular L's [steady] is linearised on M_f, and neither sweep takes it
    # (tests/cli/test_singular_command.py checks the refusal)
    found = {str(p.relative_to(ROOT)) for folder in ("examples", "tests")
             for p in (ROOT / folder).rglob("*.toml") if "\n[steady]" in p.read_text()
             and "singular" not in p.parts}
    assert found == set(SWEEPS)


def both(path, name, grid):
    """(the command's Sweep, the study's Dataset) over ``name`` = ``grid``: the command's
    sweep as ``nhham linearize --sweep`` runs it (:func:`~nhham.journeys.stability.linearize`
    calls :func:`~nhham.journeys.stability.sweep_scene` with the scene's checked
    generator; here without the single point's exact Jacobian and the open loop, whose
    models the sweep does not read)."""
    start, stop, count = grid.split(":")
    values = np.linspace(float(start), float(stop), int(count))
    scene = load_scene(ROOT / path)
    system = scene.steady_system()
    model = numeric_model(system)
    swept = sweep_scene(scene, system, model, name, values,
                        generator=symmetry_generator(scene, system, model))
    ds = sweep(str(ROOT / path), "linearize", [f"{name}={grid}"], workers=1).dataset
    return swept, ds


def test_the_command_s_sweep_is_sweep_scene():
    """The journey's ``sweep`` payload is :func:`sweep_scene`'s (the route ``both``
    takes), on the forced sleigh."""
    path, (name, grid) = "tests/study/scenes/forced_sleigh.toml", SWEEPS[
        "tests/study/scenes/forced_sleigh.toml"]
    start, stop, count = grid.split(":")
    values = np.linspace(float(start), float(stop), int(count))
    journey = linearize(str(ROOT / path), sweep=(name, values)).payload["sweep"]
    swept, _ = both(path, name, grid)
    assert journey.to_dict() == swept.to_dict()


def boundaries(ds):
    """The study's crossings as (value, kind, direction)."""
    value = ds["boundary"].values
    kind = ds["boundary_kind"].values
    direction = ds["boundary_direction"].values
    return [(float(value[i]), "real" if kind[i] == 0 else "complex", int(direction[i]))
            for i in range(value.size) if np.isfinite(value[i])]


@pytest.mark.parametrize("path", sorted(SWEEPS))
def test_the_command_s_sweep_is_the_study(path):
    name, grid = SWEEPS[path]
    swept, ds = both(path, name, grid)
    assert np.abs(swept.values - ds[name].values).max() <= 1e-15
    assert [{True: 1, False: 0, None: -1}[s] for s in swept.stable] == \
        ds["verdict"].values.tolist()
    assert (ds["status"].values == 0).all()
    ev = ds["eigenvalue_real"].values + 1j * ds["eigenvalue_imag"].values
    for got, want in zip(swept.eigenvalues, ev):
        assert np.abs(got - want).max(initial=0.0) <= 1e-9 * max(1.0, np.abs(want).max(
            initial=0.0))
    command = [(c.value, c.kind, c.direction) for c in swept.crossings]
    study = boundaries(ds)
    assert len(command) == len(study), (command, study)
    for (a, kind_a, dir_a), (b, kind_b, dir_b) in zip(command, study):
        assert abs(a - b) <= 1e-9 and (kind_a, dir_a) == (kind_b, dir_b), (command, study)
    assert len(swept.unlocated) == int(ds["boundary_unlocated"].values)
    if path.endswith("forced_sleigh.toml"):
        # U* = -c / (m a) = -0.375; the drag's touch at U = 0 is no crossing
        assert command == [(pytest.approx(-0.375, abs=1e-12), "real", -1)]
