"""Tests of nhham.system.scene: loading and validating scene files (their [initial] data
is checked in test_initial.py, writing them in test_scene_dump.py)."""

from __future__ import annotations

import dataclasses
import math
import pathlib
import shutil
import tomllib

import pytest
import sympy as sp

import nhham.errors as errors
from nhham.errors import (
    ParseError,
    SceneError,
)
from nhham.system.initial import check_initial
from nhham.system.scene import (
    MAX_SCENE_BYTES,
    Scene,
    SimulateOptions,
    load_scene,
    loads_scene,
)

from handmade import DISK_INITIAL as INITIAL
from handmade import DISK_SCENE as DISK
from handmade import DISK_SIMULATE as SIMULATE
from handmade import same

BAD = pathlib.Path(__file__).parent / "scenes_bad"
MANIFEST = tomllib.loads((BAD / "expected.toml").read_text(encoding="utf-8"))

x, y, theta, phi = sp.symbols("x y theta phi")
x_dot, y_dot, theta_dot, phi_dot = sp.symbols("x_dot y_dot theta_dot phi_dot")
m, I1, I2, R = sp.symbols("m I1 I2 R")


# ------------------------------------------------------------- good scenes
def test_rolling_disk_loads():
    scene = loads_scene(DISK + INITIAL + SIMULATE, source="disk.toml")
    assert isinstance(scene, Scene)
    assert scene.name == "vertical rolling disk"
    assert scene.description == "a disk rolling upright without slipping"
    assert scene.source == "disk.toml"
    system = scene.system
    assert system.coordinates == (x, y, theta, phi)
    assert system.velocities == (x_dot, y_dot, theta_dot, phi_dot)
    assert set(system.parameters) == {m, I1, I2, R}
    assert dict(system.parameter_values) == {m: 1.0, I1: 0.5, I2: 0.25, R: 1.0}
    assert same(system.lagrangian,
                m * (x_dot**2 + y_dot**2) / 2 + I1 * theta_dot**2 / 2 + I2 * phi_dot**2 / 2)
    assert system.constraints == (x_dot - R * sp.cos(theta) * phi_dot,
                                  y_dot - R * sp.sin(theta) * phi_dot)
    assert dict(scene.initial) == {"x": 0.0, "y": 0.0, "theta": 0.0, "phi": 0.0,
                                   "x_dot": 2.0, "y_dot": 0.0, "theta_dot": 1.0, "phi_dot": 2.0}
    assert scene.simulate == SimulateOptions(t_end=10.0, method="DOP853", rtol=1e-10)
    assert scene.simulate.given() == {"t_end": 10.0, "method": "DOP853", "rtol": 1e-10}


def test_scene_without_optional_tables():
    scene = loads_scene(DISK)
    assert scene.initial is None
    assert scene.simulate == SimulateOptions()
    assert scene.simulate.given() == {}
    assert check_initial(scene) == {}


def test_scene_is_frozen():
    scene = loads_scene(DISK + INITIAL)
    with pytest.raises(dataclasses.FrozenInstanceError):
        scene.name = "other"
    with pytest.raises(TypeError):
        scene.initial["x"] = 1.0


def test_minimal_scene_and_defaults():
    scene = loads_scene('coordinates = ["q"]\nlagrangian = "q_dot**2/2 - q**2/2"\n')
    assert scene.name == "" and scene.description == ""
    assert scene.system.coordinates == (sp.Symbol("q"),)
    assert scene.system.constraints == () and scene.system.holonomic == ()


def test_load_scene_from_file_with_bom(tmp_path):
    path = tmp_path / "disk.toml"
    path.write_bytes(b"\xef\xbb\xbf" + (DISK + INITIAL).encode("utf-8"))
    scene = load_scene(path)
    assert scene.source == str(path)
    assert scene.name == "vertical rolling disk"


def test_special_names_are_ordinary_parameters():
    text = """
coordinates = ["x", "y", "z"]
parameters = { I = 2.0, E = 3.0, S = 1.0, N = 4.0, beta = 0.5, gamma = 0.25, lambda = 1.5 }
lagrangian = "I*x_dot**2/2 + E*y_dot**2/2 + S*z_dot**2/2 - N*x - beta*y - gamma*z"
constraints = ["x_dot - lambda*y_dot"]
"""
    system = loads_scene(text).system
    I, E, S, N, lam = sp.symbols("I E S N lambda")
    assert system.lagrangian.coeff(sp.Symbol("x_dot") ** 2) == I / 2
    assert system.constraints == (sp.Symbol("x_dot") - lam * sp.Symbol("y_dot"),)
    assert system.parameter_values[lam] == 1.5
    assert system.parameter_values[I] == 2.0


def test_unicode_names():
    text = """
coordinates = ["θ", "φ"]
parameters = { "μ" = 2.0 }
lagrangian = "μ*(θ_dot**2 + φ_dot**2)/2"
"""
    system = loads_scene(text).system
    assert system.coordinates == sp.symbols("θ φ")


def test_symbolic_parameters_need_no_value():
    text = DISK.replace(", R = 1.0 }", ' }\nsymbolic_parameters = ["R"]')
    system = loads_scene(text).system
    assert R in system.parameters
    assert R not in system.parameter_values


def test_multiline_lagrangian():
    text = DISK.replace(
        'lagrangian = "m*(x_dot**2 + y_dot**2)/2 + I1*theta_dot**2/2 + I2*phi_dot**2/2"',
        'lagrangian = """\nm*(x_dot**2 + y_dot**2)/2\n  + I1*theta_dot**2/2\n  + I2*phi_dot**2/2\n"""',
    )
    assert same(loads_scene(text).system.lagrangian,
                m * (x_dot**2 + y_dot**2) / 2 + I1 * theta_dot**2 / 2 + I2 * phi_dot**2 / 2)


def test_user_text_is_not_changed():
    scene = loads_scene(DISK.replace('"vertical rolling disk"', '"  spaced  name "'))
    assert scene.name == "  spaced  name "


# -------------------------------------------------------------- bad scenes
def test_manifest_covers_every_bad_scene():
    files = {p.name for p in BAD.glob("*.toml")} - {"expected.toml"}
    assert files == set(MANIFEST)
    assert len(files) >= 30


@pytest.mark.parametrize("filename", sorted(MANIFEST))
def test_bad_scene(filename, tmp_path, monkeypatch):
    expected = MANIFEST[filename]
    error_class = getattr(errors, expected["error"])
    # Run in an empty directory so that an injection would leave a trace.
    shutil.copy(BAD / filename, tmp_path / filename)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(error_class) as info:
        read_every_table(load_scene(filename))
    assert type(info.value) is error_class, f"{type(info.value).__name__}: {info.value}"
    message = str(info.value)
    for fragment in expected["contains"]:
        assert fragment in message, f"{fragment!r} not in {message!r}"
    if "key" in expected:  # the key the command's JSON error names
        assert info.value.key == expected["key"]
    assert not (tmp_path / "PWNED").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == [filename]


def read_every_table(scene):
    """Read the tables only some commands read (their problems are raised then)."""
    scene.simulate.given()
    if scene.initial_given is not None:
        scene.checked_initial()
    if scene.steady is not None:
        scene.steady.expressions
    if scene.symmetry is not None:
        scene.symmetry.components
    tuple(scene.contacts), dict(scene.control)
    return scene


def test_scene_errors_list_every_problem():
    """Every problem of what all commands read at once; a table only some read (here
    [simulate]) is refused when read, with its own problems."""
    with pytest.raises(SceneError) as info:
        load_scene(BAD / "several_problems.toml")
    assert len(info.value.problems) == 2
    assert not any("simulate" in p for p in info.value.problems)
    scene = loads_scene((BAD / "several_problems.toml").read_text().replace(
        "m = nan", "m = 1.0").replace("holonomc", "holonomic"))
    assert scene.system.n == 4
    with pytest.raises(SceneError, match="simulate.methd: unknown key; did you mean 'method'"):
        scene.simulate.given()


def test_a_number_may_be_an_expression_in_the_parameters():
    """t_end = 7 pi/Omega and I = m a^2, evaluated at the values (--set too); a broken
    [simulate] does not stop what does not read it."""
    text = DISK.replace("I1 = 0.5", 'I1 = "m*R**2/2"') + '\n[simulate]\nt_end = "7*pi/m"\n'
    scene = loads_scene(text)
    assert scene.system.parameter_values[I1] == 0.5
    assert scene.simulate.t_end == pytest.approx(7 * math.pi)
    scene = loads_scene(text, values={"m": 2.0})
    assert scene.system.parameter_values[I1] == 1.0
    assert scene.simulate.t_end == pytest.approx(3.5 * math.pi)
    bad = loads_scene(text.replace("7*pi/m", "-7*pi/m"))
    assert bad.system.n == 4
    with pytest.raises(SceneError, match=r"simulate.t_end: must be positive.*-7\*pi/m"):
        bad.simulate.t_end
    with pytest.raises(SceneError, match="parameters.I1.*depends on itself"):
        loads_scene(text.replace('"m*R**2/2"', '"I1/2"'))
    with pytest.raises(SceneError, match="parameters.I1.*uses R, which has no value"):
        loads_scene(text.replace(", R = 1.0 }", ' }\nsymbolic_parameters = ["R"]'))


def test_parse_errors_list_every_expression():
    text = DISK.replace("m*(", "mm*(").replace("R*sin", "R*sinn")
    with pytest.raises(ParseError) as info:
        loads_scene(text)
    assert len(info.value.problems) == 2
    assert "lagrangian: unknown name 'mm'; did you mean 'm'?" in str(info.value)
    assert "constraints[1]: unknown function 'sinn'; did you mean 'sin'?" in str(info.value)


def test_non_smooth_lagrangian_gives_an_input_error():
    text = 'coordinates = ["x", "y"]\nlagrangian = "Abs(x_dot)**2 + y_dot**2"\n'
    with pytest.raises(errors.InputError, match="lagrangian: Abs\\(x_dot\\) is not smooth"):
        loads_scene(text)


# ------------------------------------------------------- generated bad files
def write(tmp_path, content, name="scene.toml"):
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8")
    return path


def test_binary_file(tmp_path):
    path = write(tmp_path, b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xff\xfe\x00\x01")
    with pytest.raises(SceneError, match="not a UTF-8 text file"):
        load_scene(path)


def test_nul_bytes_in_valid_utf8(tmp_path):
    path = write(tmp_path, b"coordinates = [\"x\"]\x00\x00\n")
    with pytest.raises(SceneError, match="NUL"):
        load_scene(path)


def test_file_larger_than_limit_is_refused_before_parsing(tmp_path):
    path = write(tmp_path, "# " + "x" * MAX_SCENE_BYTES + "\n")
    with pytest.raises(SceneError, match="too large"):
        load_scene(path)


def test_one_megabyte_expression(tmp_path):
    huge = "+".join(["x_dot**2"] * (1_000_000 // 9))
    path = write(tmp_path, DISK.replace(
        '"m*(x_dot**2 + y_dot**2)/2 + I1*theta_dot**2/2 + I2*phi_dot**2/2"', f'"{huge}"'))
    assert path.stat().st_size > 1_000_000
    with pytest.raises(ParseError, match="lagrangian: expression too long"):
        load_scene(path)


def test_many_terms_under_the_length_limit(tmp_path):
    many = "+".join(["x_dot"] * 40_000)
    with pytest.raises(ParseError, match="^lagrangian: "):
        loads_scene(DISK.replace(
            '"m*(x_dot**2 + y_dot**2)/2 + I1*theta_dot**2/2 + I2*phi_dot**2/2"', f'"{many}"'))


@pytest.mark.parametrize("depth", [300, 20_000])
def test_deeply_nested_parentheses(depth):
    nested = "(" * depth + "x_dot" + ")" * depth
    text = DISK.replace('"x_dot - R*cos(theta)*phi_dot"', f'"{nested}"')
    with pytest.raises(ParseError, match="^constraints\\[0\\]: .*nested"):
        loads_scene(text)


def test_deeply_nested_toml_arrays():
    for value in ["[" * 50_000 + "]" * 50_000, "{a=" * 50_000 + "1" + "}" * 50_000]:
        with pytest.raises(SceneError, match="nested too deeply"):
            loads_scene(DISK + "deep = " + value + "\n")


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(SceneError, match="cannot read scene file"):
        load_scene(tmp_path / "nope.toml")
    with pytest.raises(SceneError, match="cannot read scene file"):
        load_scene(tmp_path)


def test_non_string_text():
    with pytest.raises(SceneError, match="expected scene text"):
        loads_scene(DISK.encode())


@pytest.mark.parametrize(
    "expression",
    [
        "__import__('os').system('touch PWNED')",
        "x.__class__.__base__.__subclasses__()",
        "(lambda: __import__('os').system('touch PWNED'))()",
        "__builtins__",
        "f'{__import__(\\\"os\\\").system(\\\"touch PWNED\\\")}'",
        "eval('1')",
        "exec('open(\\\"PWNED\\\", \\\"w\\\")')",
        "open('PWNED', 'w')",
        "sin.__globals__",
        "[c for c in ().__class__.__bases__]",
    ],
)
def test_injection_attempts_do_nothing(expression, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    text = DISK.replace('"y_dot - R*sin(theta)*phi_dot"', f'"{expression}"')
    with pytest.raises(ParseError, match="^constraints\\[1\\]: "):
        loads_scene(text)
    assert list(tmp_path.iterdir()) == []
