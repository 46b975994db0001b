"""The layers of ``nhham``, read from the imports of every module (``ast``, nothing imported).

Layers form a tree, each importing only the layers listed for it in :data:`MAY_IMPORT`
(and, through them, nothing above): the exact side ``system`` < ``lagrangian`` <
``hamiltonian`` < ``verdict``, and beside it ``numerics`` (on ``lagrangian``, through its
bridge); ``render`` (text, LaTeX, JSON and figures of results) on both; ``journeys`` (what
a user does with a scene) on ``render``; ``study`` on ``journeys``; ``cli`` on top.
The top-level modules ``errors``, ``settings``, ``lazy``, ``budget``, ``progress`` and ``autonomy`` are the
base: every layer may import them and they import nothing of the package's layers. ``nhham/__init__.py`` (the
public API, re-exported) and ``nhham/__main__.py`` are exempt. Rules:

1. a module imports only from its own layer, the layers :data:`MAY_IMPORT` lists for it or
   the base (module-level and function-level imports alike; ``if TYPE_CHECKING:`` blocks
   are ignored);
2. no module imports a private name (``_x``) from another module;
3. nothing under ``nhham/numerics/`` imports sympy, at module level or inside a function,
   except ``nhham.numerics.codegen`` (the one bridge in). The other numerics modules import
   from the lower layers only through the bridge, and only inside a function (a numeric
   model built from a System), so that they never import sympy by themselves;
4. no import circles between modules.

:func:`check_layers` takes the directory that holds the package, so it runs as well on a
temporary copy with a planted violation. A planted upward import (the Lagrangian side
importing the command) is reported, and removing the plant makes the tree clean again:

>>> import tempfile
>>> tmp = Path(tempfile.mkdtemp())
>>> _ = plant(tmp, "nhham/lagrangian/bad.py", "from nhham.cli.main import main\\n")
>>> for problem in check_layers(tmp):
...     print(problem)
nhham.lagrangian.bad: imports nhham.cli.main (layer cli is not beneath lagrangian)
>>> (tmp / "nhham/lagrangian/bad.py").unlink()
>>> check_layers(tmp)
[]
"""

from __future__ import annotations

import ast
import doctest
import functools
import sys
from pathlib import Path

import networkx as nx
import pytest

PACKAGE = "nhham"
#: Each layer -> the layers it may import (the tree, drawn from the bottom up).
MAY_IMPORT = {
    "system": (),
    "lagrangian": ("system",),
    "hamiltonian": ("system", "lagrangian"),
    "verdict": ("system", "lagrangian", "hamiltonian"),
    "numerics": ("system", "lagrangian"),
    "render": ("system", "lagrangian", "hamiltonian", "verdict", "numerics"),
    "journeys": ("system", "lagrangian", "hamiltonian", "verdict", "numerics", "render"),
    "study": ("system", "lagrangian", "hamiltonian", "verdict", "numerics", "render",
              "journeys"),
    "problems": ("system", "lagrangian", "hamiltonian", "verdict", "numerics", "render",
                 "journeys"),
    "cli": ("system", "lagrangian", "hamiltonian", "verdict", "numerics", "render",
            "journeys", "study", "problems"),
}
LAYERS = tuple(MAY_IMPORT)
BASE = ("errors", "settings", "lazy", "budget", "progress", "autonomy")
EXEMPT = ("nhham", "nhham.__main__")
NUMERICS = "nhham.numerics"
BRIDGE = "nhham.numerics.codegen"
ROOT = Path(__file__).resolve().parents[1]


# ----------------------------------------------------------------- reading
def _module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _imports(tree: ast.AST, module: str, is_package: bool):
    """(imported module, names, line, inside a function) for every import statement."""
    package = module if is_package else module.rpartition(".")[0]
    found = []

    def visit(node, in_function):
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            for child in node.orelse:
                visit(child, in_function)
            return
        if isinstance(node, ast.Import):
            for alias in node.names:
                found.append((alias.name, (), node.lineno, in_function))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            found.append((target, tuple(a.name for a in node.names), node.lineno, in_function))
        inner = in_function or isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef,
                                                 ast.Lambda))
        for child in ast.iter_child_nodes(node):
            visit(child, inner)

    visit(tree, False)
    return found


def read_package(root: Path, package: str = PACKAGE) -> dict:
    """``{module: [(imported module, names, line, in_function), ...]}`` under ``root/package``."""
    modules = {}
    for path in sorted((root / package).rglob("*.py")):
        name = _module_name(path, root)
        modules[name] = _imports_of(path.read_text(encoding="utf-8"), name,
                                    path.name == "__init__.py")
    return modules


@functools.lru_cache(maxsize=None)
def _imports_of(text: str, module: str, is_package: bool) -> tuple:
    # The planted copies repeat the package's text: each module is parsed once per run.
    return tuple(_imports(ast.parse(text), module, is_package))


# ---------------------------------------------------------------- checking
def _layer(module: str):
    """Index of the module's layer; -1 for the base; None for the exempt top."""
    parts = module.split(".")
    if module in EXEMPT or parts[0] != PACKAGE:
        return None
    if len(parts) > 1 and parts[1] in BASE:
        return -1
    if len(parts) > 1 and parts[1] in LAYERS:
        return LAYERS.index(parts[1])
    return None


def _resolve(target: str, names, modules) -> list:
    """The package modules an import statement reaches (``from a import b`` may name a module)."""
    out = []
    for name in names:
        if f"{target}.{name}" in modules:
            out.append(f"{target}.{name}")
    if len(out) < len(names) or not names:
        out.append(target)
    return out


def _under(module: str, prefix: str) -> bool:
    return module == prefix or module.startswith(prefix + ".")


def check_layers(root, package: str = PACKAGE) -> list:
    """Every violation of the rules of this module's docstring in ``root/package``.

    Parameters
    ----------
    root : path
        Directory holding the package directory (the repository root, or a temporary copy).

    Returns
    -------
    list of str
        One line per violation, ``"<module>: <what>"``; empty when the tree is clean.
    """
    root = Path(root)
    modules = read_package(root, package)
    problems = []
    graph = nx.DiGraph()
    graph.add_nodes_from(modules)
    for module, imports in modules.items():
        own = _layer(module)
        for target, names, line, in_function in imports:
            if target is None:
                continue
            is_sympy = target == "sympy" or target.startswith("sympy.")
            if _under(module, NUMERICS) and not _under(module, BRIDGE) and is_sympy:
                where = "inside a function" if in_function else "at module level"
                problems.append(f"{module}: imports {target} {where} (line {line}); "
                                f"only {BRIDGE} may")
            if not _under(target, package):
                continue
            for private in (n for n in names if n.startswith("_") and n != "__version__"):
                if f"{target}.{private}" not in modules:
                    problems.append(f"{module}: imports the private name {private} from "
                                    f"{target} (line {line})")
            for reached in _resolve(target, names, modules):
                if reached == module:
                    continue
                graph.add_edge(module, reached)
                if own is None:
                    continue
                theirs = _layer(reached)
                if theirs is None and reached not in modules:
                    continue  # not a module of this package (e.g. an optional piece)
                if theirs is None:
                    problems.append(f"{module}: imports {reached} (the public package; import "
                                    f"from the defining module)")
                elif own == -1 and theirs != -1:
                    problems.append(f"{module}: imports {reached} (the base imports no layer)")
                elif theirs not in (-1, own) and LAYERS[theirs] not in MAY_IMPORT[LAYERS[own]]:
                    problems.append(f"{module}: imports {reached} (layer {LAYERS[theirs]} is "
                                    f"not beneath {LAYERS[own]})")
                elif (_under(module, NUMERICS) and not _under(module, BRIDGE)
                      and not _under(reached, NUMERICS) and theirs != -1):
                    problems.append(f"{module}: imports {reached} (numerics reaches the lower "
                                    f"layers only through {BRIDGE})")
                elif (_under(module, NUMERICS) and not _under(module, BRIDGE)
                      and _under(reached, BRIDGE) and not in_function):
                    problems.append(f"{module}: imports {reached} at module level (line {line}); "
                                    f"import the bridge inside the function that needs it")
    for cycle in sorted(sorted(c) for c in nx.simple_cycles(graph)):
        problems.append(f"{cycle[0]}: import circle {' -> '.join(cycle)}")
    return problems


def plant(root: Path, relative: str, source: str) -> Path:
    """A copy of the real package under ``root`` with ``relative`` written as ``source``."""
    import shutil

    target = root / PACKAGE
    if not target.exists():
        shutil.copytree(ROOT / PACKAGE, target,
                        ignore=shutil.ignore_patterns("__pycache__", "*.c", "*.h"))
    path = root / relative
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(source, encoding="utf-8")
    return root


# ------------------------------------------------------------------ tests
def test_the_package_keeps_its_layers():
    assert check_layers(ROOT) == []


def test_the_docstring_example_runs():
    """The planted upward import in the module docstring is reported, then gone."""
    result = doctest.testmod(sys.modules[__name__], extraglobs={"Path": Path},
                             optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted >= 4 and result.failed == 0


@pytest.mark.parametrize("relative, source, expected", [
    ("nhham/lagrangian/bad.py", "from nhham.cli.main import main\n",
     "nhham.lagrangian.bad: imports nhham.cli.main (layer cli is not beneath lagrangian)"),
    ("nhham/system/bad.py", "def f():\n    from nhham.hamiltonian import side\n",
     "nhham.system.bad: imports nhham.hamiltonian.side (layer hamiltonian is not beneath system)"),
    ("nhham/numerics/bad.py", "def f():\n    import sympy\n",
     "nhham.numerics.bad: imports sympy inside a function (line 2); "
     "only nhham.numerics.codegen may"),
    ("nhham/numerics/bad.py", "from sympy.core import Symbol\n",
     "nhham.numerics.bad: imports sympy.core at module level (line 1); "
     "only nhham.numerics.codegen may"),
    ("nhham/numerics/bad.py", "from nhham.lagrangian.geometry import lagrangian_geometry\n",
     "nhham.numerics.bad: imports nhham.lagrangian.geometry (numerics reaches the lower "
     "layers only through nhham.numerics.codegen)"),
    ("nhham/numerics/bad.py", "from nhham.numerics.codegen import numeric_model\n",
     "nhham.numerics.bad: imports nhham.numerics.codegen at module level (line 1); "
     "import the bridge inside the function that needs it"),
    ("nhham/hamiltonian/bad.py", "from nhham.lagrangian.geometry import _private\n",
     "nhham.hamiltonian.bad: imports the private name _private from nhham.lagrangian.geometry "
     "(line 1)"),
    ("nhham/lagrangian/bad.py", "from nhham import System\n",
     "nhham.lagrangian.bad: imports nhham (the public package; import from the defining "
     "module)"),
    ("nhham/settings.py", "from nhham.system.naming import velocity_name\n",
     "nhham.settings: imports nhham.system.naming (the base imports no layer)"),
    ("nhham/lagrangian/bad.py", "from . import bad2\n", None),
    ("nhham/lagrangian/bad.py",  # typing-only imports are not run
     "if TYPE_CHECKING:\n    from nhham.cli.main import main\n", None),
])
def test_a_planted_violation_is_reported(tmp_path, relative, source, expected):
    plant(tmp_path, relative, source)
    if relative == "nhham/lagrangian/bad.py" and source.startswith("from . import"):
        plant(tmp_path, "nhham/lagrangian/bad2.py", "from nhham.lagrangian import bad\n")
        expected = ("nhham.lagrangian.bad: import circle nhham.lagrangian.bad -> "
                    "nhham.lagrangian.bad2")
    problems = check_layers(tmp_path)
    assert problems == ([] if expected is None else [expected])


# ------------------------------------------------------------ module sizes
#: Longest module of the package, in lines: a longer one is split by concept.
MAX_LINES = 700
#: Over MAX_LINES for now: none (an entry here is a debt, and this list only shrinks).
ALLOWED_LONG_FOR_NOW: tuple = ()


def long_modules(root, package: str = PACKAGE, limit: int = MAX_LINES) -> list:
    """``"<path>: <n> lines"`` for every module of ``root/package`` longer than ``limit``."""
    root = Path(root)
    out = []
    for path in sorted((root / package).rglob("*.py")):
        n = len(path.read_text(encoding="utf-8").splitlines())
        if n > limit:
            out.append(f"{path.relative_to(root).as_posix()}: {n} lines")
    return out


def test_no_module_is_longer_than_the_limit():
    too_long = [line for line in long_modules(ROOT)
                if line.split(":")[0] not in ALLOWED_LONG_FOR_NOW]
    assert too_long == []


def test_a_planted_long_module_is_reported(tmp_path):
    plant(tmp_path, "nhham/system/long.py", "x = 1\n" * (MAX_LINES + 1))
    assert f"nhham/system/long.py: {MAX_LINES + 1} lines" in long_modules(tmp_path)


# ------------------------------------------------- Submanifold's own methods
SUBMANIFOLD = "nhham/lagrangian/submanifold.py"


def submanifold_private_uses(root, package: str = PACKAGE) -> list:
    """``"<module>:<line>: <expr>"`` for every use, outside ``submanifold.py``, of a
    private member (``_x``) of :class:`~nhham.lagrangian.submanifold.Submanifold`:
    its methods and the attributes its methods set, on anything but ``self``."""
    root = Path(root)
    tree = ast.parse((root / SUBMANIFOLD).read_text(encoding="utf-8"))
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Submanifold")
    private = {n.name for n in cls.body if isinstance(n, ast.FunctionDef)}
    private |= {n.attr for n in ast.walk(cls) if isinstance(n, ast.Attribute)
                and isinstance(n.value, ast.Name) and n.value.id == "self"}
    private = {n for n in private if n.startswith("_") and not n.endswith("__")}
    out = []
    for path in sorted((root / package).rglob("*.py")):
        if path == root / SUBMANIFOLD:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if (isinstance(node, ast.Attribute) and node.attr in private
                    and not (isinstance(node.value, ast.Name) and node.value.id == "self")):
                out.append(f"{_module_name(path, root)}:{node.lineno}: {ast.unparse(node)}")
    return out


def test_no_module_uses_a_private_member_of_submanifold():
    assert submanifold_private_uses(ROOT) == []


def test_a_planted_use_of_a_submanifold_private_is_reported(tmp_path):
    plant(tmp_path, "nhham/lagrangian/bad.py", "def f(manifold):\n"
                                               "    return manifold._zero_level(0.0)\n")
    assert submanifold_private_uses(tmp_path) == [
        "nhham.lagrangian.bad:2: manifold._zero_level"]
