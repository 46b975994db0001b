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
    for name in ("nhham.classify", "nhham.linearize", "nhham.Linearization",
                 "nhham.sweep_steady", "nhham.dump_scene", "nhham.NumericModel.rhs"):
        assert f'id="{name}"' in api, name


def test_cli_doc_lists_every_result_key():
    """docs/cli.rst names every key of every command's result in the JSON Schema
    (linearize's were missing)."""
    from nhham.render.schema import output_schema

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


# What changes from run to run in a notebook's outputs and is not the tutorial's point:
# timings, object addresses, and which backend ran (the C library may still be compiling).
_VOLATILE = [(re.compile(r"wall time [0-9.e+-]+ s"), "wall time <t> s"),
             (re.compile(r"(wall_time_s[^0-9]*)[0-9.e+-]+"), r"\1<t>"),
             (re.compile(r"\b[0-9.]+(?:e[+-]?\d+)? ?(?:ms|µs|s)\b"), "<t>"),
             (re.compile(r"0x[0-9a-fA-F]+"), "0x?"),
             (re.compile(r"\b(?:c|numpy) backend\b"), "<backend> backend")]
_NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def _shown(output) -> dict:
    """{mime or "stream": text} of one output, the volatile parts normalised (images:
    only that there is one)."""
    if output["output_type"] == "stream":
        texts = {"stream": "".join(output["text"])}
    else:
        texts = {k: ("<image>" if k.startswith("image/") else
                     "".join(v) if isinstance(v, list) else str(v))
                 for k, v in output["data"].items()}
    for key, text in texts.items():
        for pattern, by in _VOLATILE:
            text = pattern.sub(by, text)
        texts[key] = text
    return texts


def _same_text(fresh: str, stored: str) -> bool:
    """The same words, and numbers equal to 1e-6 relative (1e-9 absolute: round-off
    residuals of 1e-13 differ between the compiled and the numpy kernels)."""
    if _NUMBER.sub("#", fresh) != _NUMBER.sub("#", stored):
        return False
    for a, b in zip(_NUMBER.findall(fresh), _NUMBER.findall(stored)):
        x, y = float(a), float(b)
        if abs(x - y) > 1e-6 * max(abs(x), abs(y)) + 1e-9:
            return False
    return True


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_tutorial_notebook_runs_and_shows_its_stored_outputs(name):
    """Every code cell, in order, in a fresh interpreter from the repository root (the
    cells carry their own assertions), by docs/tutorials/execute.py; what each cell shows
    is what the notebook stores (timings, addresses and the backend aside; numbers to
    1e-6): a stale stored output fails (rerun execute.py to refresh them)."""
    pytest.importorskip("matplotlib")
    # laid out at the width of piped output, as the stored outputs are (xdist's workers
    # set COLUMNS to their own terminal's)
    env = dict(os.environ, MPLBACKEND="Agg", COLUMNS="100")
    proc = subprocess.run([sys.executable, str(DOCS / "tutorials" / "execute.py"), "--stdout",
                           name], capture_output=True, text=True, timeout=600, cwd=ROOT,
                          env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    fresh = json.loads(proc.stdout.strip().splitlines()[-1])
    nb = json.loads((DOCS / "tutorials" / name).read_text())
    stored = [c["outputs"] for c in nb["cells"] if c["cell_type"] == "code"]
    assert len(fresh) == len(stored)
    for i, (now, kept) in enumerate(zip(fresh, stored)):
        assert [o["output_type"] for o in now] == [o["output_type"] for o in kept], (name, i)
        for a, b in zip(map(_shown, now), map(_shown, kept)):
            assert sorted(a) == sorted(b), (name, i)
            for key in a:
                assert _same_text(a[key], b[key]), (name, i, key, a[key], b[key])


def test_stale_notebook_outputs_are_told_apart():
    """The comparison above is not blind: a changed word or a number off by 1e-4 is a
    difference; a timing, an address, the backend or a round-off residual is not."""
    out = {"output_type": "stream", "text": ["energy drift 7.31e-13, wall time 0.0002 s, c "
                                             "backend at 0x7f00ab, x = 16.04835336\n"]}
    same = {"output_type": "stream", "text": ["energy drift 7.30e-13, wall time 0.09 s, numpy "
                                              "backend at 0x55aa01, x = 16.048353361\n"]}
    assert _same_text(_shown(out)["stream"], _shown(same)["stream"])
    for changed in ("energy drift 7.31e-13, wall time 0.0002 s, c backend at 0x7f00ab, "
                    "x = 16.04995336\n",
                    "energy  drift 7.31e-13, wall time 0.0002 s, c backend at 0x7f00ab, "
                    "x = 16.04835336\n"):
        other = {"output_type": "stream", "text": [changed]}
        assert not _same_text(_shown(out)["stream"], _shown(other)["stream"])


_CONFLICT = re.compile(r"^(<{7}|={7}|>{7})(?: .*)?$", re.M)


def test_no_merge_conflict_markers_in_the_docs_or_the_readme():
    """A leftover ``=======`` line renders as text and Sphinx does not warn (it is a
    valid section underline only under a title of at most 7 characters)."""
    found = []
    for path in [ROOT / "README.md", ROOT / "DESIGN.md", ROOT / "CHANGELOG.md",
                 *DOCS.rglob("*.rst"), *DOCS.rglob("*.md"), *DOCS.rglob("*.ipynb")]:
        if "_build" in path.parts:
            continue
        lines = path.read_text().splitlines()
        for i, line in enumerate(lines):
            if not _CONFLICT.match(line.strip('" ,').replace("\\n", "")):
                continue
            # an RST title underline (or overline) of the title's length is not a marker
            title = lines[i - 1].strip() if i else ""
            if line.startswith("=") and title and len(title) <= len(line) and \
                    not _CONFLICT.match(title):
                continue
            found.append(f"{path.relative_to(ROOT)}:{i + 1}")
    assert found == []


def test_every_help_describes_the_whole_envelope():
    """``--json`` in every command's --help lists the envelope's keys, ``error`` too."""
    from nhham.cli.envelope import envelope
    from nhham.cli.main import COMMANDS, build_parser

    keys = sorted(envelope("classify", {}))
    parser = build_parser()
    sub = next(a for a in parser._actions if a.choices and "classify" in a.choices)
    for command in COMMANDS:
        text = " ".join(sub.choices[command].format_help().split())
        listed = re.search(r"envelope \{([^}]*)\}", text)
        assert listed, command
        assert sorted(k.strip() for k in listed.group(1).split(",")) == keys, command
    simulation = (DOCS / "tutorials" / "simulation.ipynb").read_text()
    for listed in re.findall(r"envelope `\{([^}]*)\}`", simulation.replace('\\n",\n    "', "")):
        assert sorted(k.strip() for k in listed.split(",")) == keys


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


@pytest.mark.parametrize("module", ["nhham.render.latex", "nhham.cli.envelope", "nhham.render.display",
                                    "nhham.system.expressions", "nhham.render.plotting",
                                    "nhham.system.scene_keys", "nhham.system.scene_numbers",
                                    "nhham.system.scene_structure", "nhham.system.scene",
                                    "nhham.progress", "nhham.lagrangian.adjugate",
                                    "nhham.journeys.reduction", "nhham.lagrangian.chaplygin",
                                    "nhham.hamiltonian.hamiltonization_points",
                                    "nhham.problems", "nhham.problems.measures",
                                    "nhham.problems.runner"])
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
                 "nhham/render/schemas/output.schema.json"):
        assert (ROOT / name).is_file(), name
    assert "BSD 3-Clause" in (ROOT / "LICENSE").read_text()
    pyproject = (ROOT / "pyproject.toml").read_text()
    assert 'license = { text = "BSD-3-Clause" }' in pyproject
    assert '"schemas/*.json"' in pyproject and '"py.typed"' in pyproject


def test_readme_command_transcripts_are_what_the_command_prints(monkeypatch):
    """Each ``$ nhham ...`` block of the README and the guide shows the command's real output (laid out
    at the width of piped output, 100 columns, whatever the terminal running the tests)."""
    import shlex

    monkeypatch.setenv("COLUMNS", "100")

    from nhham.cli.main import main

    readme = "".join(p.read_text() for p in [ROOT / "README.md", *DOCS.glob("guide-*.md")])
    blocks = re.findall(r"```\n\$ (nhham [^\n]+)\n(.*?)```", readme, re.S)
    assert len(blocks) >= 8
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


def test_the_readme_is_short_and_names_every_command():
    """A newcomer's README: at most 250 lines, its table a row per command of the parser;
    every "nhham a|b|..." list in the docs names them all."""
    from nhham.cli.main import COMMANDS

    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= 250
    rows = re.findall(r"(?m)^\| `(\w+)` \|", readme)
    assert rows == list(COMMANDS)
    for path in [ROOT / "README.md", ROOT / "DESIGN.md", *DOCS.glob("*.rst"), *DOCS.glob("*.md")]:
        for listed in re.findall(r"nhham ((?:\w+\|)+\w+)", path.read_text()):
            assert listed.split("|") == list(COMMANDS), path.name


def test_the_guide_keeps_every_section_the_readme_had():
    """Nothing lost when the README was cut: each former section heading is a heading of
    the guide."""
    guide = "".join(p.read_text() for p in DOCS.glob("guide-*.md"))
    for title in ("The command", "Scene files", "Verdicts for every parameter value",
                  "Curved configuration spaces", "Bounding the time in Python",
                  "Speed or accuracy?", "Systems of realistic size",
                  "How the code is organised", "From sympy.physics.mechanics",
                  "The bicycle, certified, and its contact forces", "Time-dependent systems",
                  "Constraints nonlinear in the velocities (Chetaev's rule)",
                  "Chaplygin reduction and Chaplygin's multiplier", "Forces and inputs",
                  "Parameter studies", "Conventions"):
        assert re.search(rf"(?m)^#+ {re.escape(title)}$", guide), title
