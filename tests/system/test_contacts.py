"""Contact points of a scene (nhham.system.contacts): structure, parsing, labels."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

import nhham
from nhham.system.contacts import contact_rows, contacts_structure
from nhham.system.scene import loads_scene

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
from make_disc_on_ground import VALUES, disc  # noqa: E402

M, G, R = VALUES["m"], VALUES["g"], VALUES["r"]


def test_the_structure_names_the_offending_key():
    problems = []
    contacts_structure({"a": {"velocity": ["x_dot"], "constraints": ["constraints[0]"]},
                        "b": {"velocity": ["0", "0", "0"], "constraints": []},
                        "c": "not a table",
                        "d": {"velocity": ["0", "0", "0"], "constraints": ["c"], "mass": 1}},
                       problems)
    assert problems[0].startswith("contacts.a.velocity: expected three expression strings")
    assert problems[1].startswith("contacts.b.constraints: expected a non-empty list")
    assert problems[2].startswith("contacts.c: expected a table")
    assert problems[3].startswith("contacts.d.mass: unknown key")
    problems = []
    assert contacts_structure(["x"], problems) is None
    assert problems == ["contacts: expected a table of [contacts.<name>] tables"]


def test_a_scene_names_its_contact_points():
    """[contacts.<name>] in a scene: parsed with the scene's parser, labels checked."""
    system, contact = disc()
    vP = contact.velocity
    from nhham.system.expressions import to_text

    text = f"""
coordinates = ["x", "y", "z", "theta", "phi", "psi"]
parameters = {{ m = {M}, g = {G}, r = {R} }}
lagrangian = "{to_text(system.lagrangian)}"
constraints = ["{to_text(system.constraints[0])}", "{to_text(system.constraints[1])}"]
holonomic = ["z - r*cos(phi)"]
[contacts.ground]
velocity = ["{to_text(vP[0])}", "{to_text(vP[1])}", "{to_text(vP[2])}"]
constraints = ["holonomic[0]", "constraints[0]", "constraints[1]"]
"""
    scene = loads_scene(text)
    (ground,) = scene.contacts
    assert ground.name == "ground" and ground.velocity == vP
    bad = text.replace('"constraints[1]"]\n', '"constraints[7]"]\n')
    with pytest.raises(nhham.NhhamError, match=r"contacts.ground.constraints.*constraints\[7\]"):
        tuple(loads_scene(bad).contacts)   # checked where it is read (simulate, derive)
    with pytest.raises(nhham.NhhamError, match=r"contacts.ground.velocity\[0\]"):
        tuple(loads_scene(text.replace(f'velocity = ["{to_text(vP[0])}"',
                                       'velocity = ["__import__(1)"')).contacts)
    system = scene.system
    assert contact_rows(system, ground) == [0, 1, 2]
