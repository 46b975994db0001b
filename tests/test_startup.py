"""Start-up: each command imports what it needs when it needs it. Checked on
``sys.modules`` in a fresh interpreter (no timing): ``nhham --version`` and the import of
the command's module load neither sympy nor numpy; a scene parse loads no scipy,
matplotlib, networkx or parameter-study (Dask, xarray, Zarr) module, and neither does a
plain classify (or derive, compare) of a small example; generating a numeric function
does not load the submodules numpy keeps lazy (its star import would)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

HEAVY = ("scipy", "matplotlib", "dask", "distributed", "xarray", "zarr", "networkx")


def loaded_after(code: str) -> set:
    """The top-level modules loaded by ``code`` in a fresh interpreter (from the root)."""
    probe = code + "\nimport sys, json\nprint(json.dumps(sorted({m.split('.')[0] for m in " \
                   "sys.modules} | {m for m in sys.modules if m.startswith('numpy.')})))"
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          cwd=ROOT, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return set(json.loads(proc.stdout.strip().splitlines()[-1]))


def test_version_loads_neither_sympy_nor_numpy():
    mods = loaded_after("import contextlib, io\nfrom nhham.__main__ import run\n"
                        "out = io.StringIO()\nwith contextlib.redirect_stdout(out):\n"
                        "    assert run(['--version']) == 0\nassert out.getvalue() == "
                        "'nhham ' + __import__('nhham').__version__ + '\\n'")
    assert not mods & {"sympy", "numpy", "mpmath", *HEAVY}, sorted(mods & {"sympy", "numpy"})


def test_the_command_module_imports_light():
    mods = loaded_after("import nhham.cli.main")
    assert not mods & {"sympy", "numpy", "mpmath", *HEAVY}


@pytest.mark.parametrize("example", ["snakeboard.toml", "bicycle_steer_control.toml"])
def test_a_scene_parse_loads_no_numerics_plotting_or_study_module(example):
    mods = loaded_after("from nhham.system.scene import load_scene\n"
                        f"load_scene('examples/{example}')")
    assert "sympy" in mods                  # the parse itself
    assert not mods & set(HEAVY), sorted(mods & set(HEAVY))


@pytest.mark.parametrize("command, says", [("classify", "status                  determined"),
                                           ("derive", "projected field P(xi_L)"),
                                           ("compare", "AGREE exactly")])
def test_a_plain_classification_loads_no_graph_numerics_plotting_or_study_module(command, says):
    """networkx is imported only when someone asks for the provenance graph."""
    mods = loaded_after("import contextlib, io\nfrom nhham.__main__ import run\n"
                        "out = io.StringIO()\nwith contextlib.redirect_stdout(out):\n"
                        f"    assert run(['{command}', 'examples/rolling_disk.toml']) == 0\n"
                        f"assert {says!r} in out.getvalue(), out.getvalue()")
    assert "sympy" in mods
    assert not mods & set(HEAVY), sorted(mods & set(HEAVY))
    later = loaded_after("from nhham import load_scene, analyze_constraints\n"
                         "a = analyze_constraints(load_scene('examples/rolling_disk.toml')"
                         ".system)\nassert a.provenance.number_of_nodes() == 2")
    assert "networkx" in later          # the graph, once asked for


def test_a_numeric_function_does_not_load_numpy_s_lazy_submodules():
    mods = loaded_after("import sympy as sp\nimport numpy as np\n"
                        "from nhham.system.evaluation import numeric_function\n"
                        "x, y = sp.symbols('x y')\n"
                        "f = numeric_function([x, y], sp.Matrix([[sp.sin(x)*sp.sqrt(y), "
                        "sp.Heaviside(x)], [sp.atan2(y, x), sp.exp(-x**2) + sp.I*0]]))\n"
                        "v = f(0.5, 2.0)\n"
                        "want = [[np.sin(0.5)*np.sqrt(2.0), 1.0], [np.arctan2(2.0, 0.5), "
                        "np.exp(-0.25)]]\n"
                        "assert np.allclose(np.asarray(v, dtype=float), want), v")
    assert not mods & {"numpy.f2py", "numpy.testing", "numpy.ctypeslib"}, sorted(mods)
