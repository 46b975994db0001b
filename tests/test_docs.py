"""The documentation works: the site builds without warnings, the tutorial
notebooks' code runs, the docstring examples hold, and the README's code runs."""

import doctest
import importlib
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def test_docs_build_without_warnings(tmp_path):
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_parser")
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html", str(DOCS),
                           str(tmp_path / "html")], capture_output=True, text=True, timeout=600,
                          cwd=ROOT)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    design = (tmp_path / "html" / "design.html").read_text()
    assert "Mathematics and conventions" in design  # DESIGN.md is the docs' own page
    api = (tmp_path / "html" / "api.html").read_text()
    assert api.count('class="sig-name') > 25
    # the public linearisation, the scipy-ready right-hand side and the scene writer
    for name in ("nhham.linearize_scene", "nhham.linearize", "nhham.Linearization",
                 "nhham.sweep_steady", "nhham.dump_scene", "nhham.NumericModel.rhs"):
        assert f'id="{name}"' in api, name


def test_cli_doc_lists_every_result_key():
    """docs/cli.rst names every key of every command's result in the JSON Schema
    (linearize's were missing)."""
    from nhham.cli.envelope import output_schema

    doc = (DOCS / "cli.rst").read_text()
    defs = output_schema()["$defs"]
    for command in ("classify", "derive", "compare", "simulate", "bench", "linearize", "sweep",
                    "classify_parametric", "parameter_case"):
        spec = defs[command]
        properties = spec.get("properties") or next(
            o["properties"] for o in spec["oneOf"] if "properties" in o)
        missing = [k for k in properties if f"``{k}``" not in doc]
        assert not missing, (command, missing)


def notebook_code(path):
    nb = json.loads(path.read_text())
    assert nb["nbformat"] == 4
    return "\n\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")


NOTEBOOKS = ["first_steps.ipynb", "simulation.ipynb", "stability.ipynb"]


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_tutorial_notebook_runs(name):
    """Every code cell, in order, in a fresh interpreter from the repository root
    (the cells carry their own assertions)."""
    pytest.importorskip("matplotlib")
    code = notebook_code(DOCS / "tutorials" / name)
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=600, cwd=ROOT, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]


def test_every_notebook_is_listed_and_stored_with_its_outputs():
    """Readers on GitHub or the docs see what each cell prints without running it: every
    code cell has run in order (docs/tutorials/execute.py) and has the outputs its code
    makes: printed text for a print, a result for a last line that is an expression."""
    import ast

    assert sorted(p.name for p in (DOCS / "tutorials").glob("*.ipynb")) == sorted(NOTEBOOKS)
    listing = (DOCS / "tutorials.rst").read_text()
    for name in NOTEBOOKS:
        assert f"tutorials/{name}" in listing, name
        nb = json.loads((DOCS / "tutorials" / name).read_text())
        code = [c for c in nb["cells"] if c["cell_type"] == "code"]
        assert [c["execution_count"] for c in code] == list(range(1, len(code) + 1)), name
        for cell in code:
            source = "".join(cell["source"])
            kinds = {o["output_type"] for o in cell["outputs"]}
            assert "error" not in kinds, (name, source[:60])
            if "print(" in source:
                assert "stream" in kinds, (name, source[:60])
            if isinstance(ast.parse(source).body[-1], ast.Expr) and "print(" not in \
                    source.splitlines()[-1]:
                assert "execute_result" in kinds, (name, source[:60])


@pytest.mark.parametrize("module", ["nhham.cli.latex", "nhham.cli.envelope", "nhham.cli.display",
                                    "nhham.system.expressions", "nhham.cli.plotting"])
def test_docstring_examples(module):
    mod = importlib.import_module(module)
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0


def test_readme_python_example_prints_what_it_says():
    readme = (ROOT / "README.md").read_text()
    code = re.search(r"## In Python\n\n```python\n(.*?)```", readme, re.S).group(1)
    printed = re.search(r"\nprints\n\n```\n(.*?)```", readme, re.S).group(1)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == printed.strip()


def test_no_dangling_design_references():
    """Every file that cites DESIGN.md can find it in the repository."""
    assert (ROOT / "DESIGN.md").is_file()
    text = (ROOT / "DESIGN.md").read_text()
    for section in ("## 2. Mathematics", "## 3. Contracts", "## 4. Shape of the code"):
        assert section in text


def test_the_paper_is_cited_by_its_title_and_journal():
    """The paper nhham implements is the Extracta Mathematicae one (1996), not the
    authors' J. Math. Phys. paper of the same year; every full citation says so."""
    sources = [ROOT / "README.md", ROOT / "DESIGN.md", *DOCS.glob("*.md"), *DOCS.glob("*.rst"),
               *(ROOT / "nhham").rglob("*.py"), *(ROOT / "tests").rglob("*.py")]
    here = Path(__file__).resolve()
    wrong = [p.name for p in sources if p.resolve() != here
             and ("J. Math. Phys" in p.read_text() or "On the geometry of non" in p.read_text())]
    assert wrong == []
    title = "Solving\nnon-holonomic Lagrangian dynamics in terms of almost product structures"
    for path in (ROOT / "DESIGN.md", DOCS / "paper-errata.md", ROOT / "README.md"):
        text = " ".join(path.read_text().split())
        assert " ".join(title.split()) in text and "Extracta Mathematicae 11 (1996) 325–347" \
            in text, path.name


def test_packaging_files():
    for name in ("LICENSE", "CHANGELOG.md", "nhham/py.typed",
                 "nhham/cli/schemas/output.schema.json"):
        assert (ROOT / name).is_file(), name
    assert "BSD 3-Clause" in (ROOT / "LICENSE").read_text()
    pyproject = (ROOT / "pyproject.toml").read_text()
    assert 'license = { text = "BSD-3-Clause" }' in pyproject
    assert '"schemas/*.json"' in pyproject and '"py.typed"' in pyproject


def test_readme_command_transcripts_are_what_the_command_prints(monkeypatch):
    """Each ``$ nhham ...`` block of the README shows the command's real output (laid out
    at the width of piped output, 100 columns, whatever the terminal running the tests)."""
    import shlex

    monkeypatch.setenv("COLUMNS", "100")

    from nhham.cli.main import main

    readme = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```\n\$ (nhham [^\n]+)\n(.*?)```", readme, re.S)
    assert len(blocks) >= 3
    for command, shown in blocks:
        import contextlib
        import io

        out = io.StringIO()
        cwd = os.getcwd()
        os.chdir(ROOT)
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
                assert main(shlex.split(command)[1:]) == 0, command
        finally:
            os.chdir(cwd)
        assert out.getvalue().strip() == shown.strip(), command
