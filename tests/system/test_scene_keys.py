"""The scene format's reference (docs/scene.rst) against the reader: every key the reader
accepts is on the page, every example on the page loads, and the page is the registry
written out."""

import dataclasses
from pathlib import Path

import pytest

from nhham.errors import SceneError
from nhham.system.contacts import CONTACT_KEYS
from nhham.system.scene import SimulateOptions, loads_scene
from nhham.system.scene_keys import BASE, SCENE_KEYS, example_scene, reference, top_level_keys
from nhham.system.scene_structure import READ_BY_COMMANDS
from tests.system.test_scene import read_every_table

DOCS = Path(__file__).resolve().parents[2] / "docs"
NAMES = {k.name for k in SCENE_KEYS}


def test_the_page_is_the_registry_written_out():
    assert (DOCS / "scene.rst").read_text() == reference(), \
        "regenerate: python -m nhham.system.scene_keys > docs/scene.rst"
    assert "scene" in (DOCS / "index.rst").read_text().split()


@pytest.mark.parametrize("name", top_level_keys())
def test_every_top_level_key_is_read_and_documented(name):
    """The reader knows the key (no 'unknown key' problem) and the page has a section."""
    loads_scene(example_scene(next(k for k in SCENE_KEYS if k.name == name)))
    assert f"``{name}``\n" in reference()


def test_an_undocumented_key_is_refused():
    with pytest.raises(SceneError, match="frobnicate: unknown key"):
        loads_scene(BASE + "frobnicate = 1\n")


def test_the_tables_keys_match_the_reader():
    simulate = {f.name for f in dataclasses.fields(SimulateOptions)}
    assert {n.split(".")[1] for n in NAMES if n.startswith("simulate.")} == simulate
    assert {n.rsplit(".", 1)[1] for n in NAMES if n.startswith("contacts.")} == \
        set(CONTACT_KEYS)
    # the tables checked only by the commands that read them are those the page says
    assert set(READ_BY_COMMANDS) == {k.name for k in SCENE_KEYS
                                     if "." not in k.name and k.read_by != ("every command",)}


@pytest.mark.parametrize("entry", [k for k in SCENE_KEYS if k.example],
                         ids=lambda k: k.name)
def test_every_example_loads_and_is_read(entry):
    """Each example, added to the base scene, loads, and its tables can be read (no
    problem is waiting where a command reads them)."""
    read_every_table(loads_scene(example_scene(entry)))


def test_every_key_of_every_example_scene_is_on_the_page():
    """The bundled examples use only documented keys (the reader would refuse others)."""
    import tomllib

    examples = Path(__file__).resolve().parents[2] / "examples"
    for path in examples.glob("*.toml"):
        data = tomllib.loads(path.read_text())
        assert set(data) <= NAMES, path.name
        for sub in data.get("simulate", {}):
            assert f"simulate.{sub}" in NAMES, path.name
