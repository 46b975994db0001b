"""Run the tutorial notebooks and store their outputs (what Jupyter would show).

Usage, from the repository's root::

    python docs/tutorials/execute.py [--stdout] [NOTEBOOK ...]

(default: every ``*.ipynb`` beside this file; ``--stdout``: print the outputs, a JSON list
per notebook with one list of outputs per code cell, instead of storing them; the docs
test compares them with the stored ones). The code cells run in order in one
namespace, in this interpreter, from the repository's root; each cell's printed text
becomes a ``stream`` output and the value of its last line, if an expression, an
``execute_result`` with ``text/plain`` and, where the object has them, ``text/latex``,
``text/html`` or (a matplotlib Figure) ``image/png``. No Jupyter installation is needed.
"""

from __future__ import annotations

import ast
import base64
import contextlib
import io
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]


def _bundle(value) -> dict:
    """The MIME bundle Jupyter would display for ``value``."""
    data = {"text/plain": repr(value)}
    for mime, method in (("text/latex", "_repr_latex_"), ("text/html", "_repr_html_")):
        shown = getattr(value, method, None)
        shown = shown() if callable(shown) else None
        if shown:
            data[mime] = shown
    if type(value).__name__ == "Figure" and hasattr(value, "savefig"):
        buffer = io.BytesIO()
        value.savefig(buffer, format="png", dpi=60)
        data["image/png"] = base64.b64encode(buffer.getvalue()).decode("ascii")
    return data


def _run_cell(source: str, namespace: dict, count: int) -> list:
    tree = ast.parse(source)
    last = tree.body.pop() if tree.body and isinstance(tree.body[-1], ast.Expr) else None
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(tree, f"<cell {count}>", "exec"), namespace)
        value = None if last is None else eval(
            compile(ast.Expression(last.value), f"<cell {count}>", "eval"), namespace)
    outputs = []
    if out.getvalue():
        outputs.append({"name": "stdout", "output_type": "stream",
                        "text": out.getvalue().splitlines(keepends=True)})
    if value is not None:
        outputs.append({"data": _bundle(value), "execution_count": count, "metadata": {},
                        "output_type": "execute_result"})
    return outputs


def execute(path: Path, store: bool = True) -> list:
    """Run ``path``'s code cells; their outputs (one list per code cell), written into the
    notebook when ``store``."""
    notebook = json.loads(path.read_text())
    namespace: dict = {"__name__": "__main__"}
    count = 0
    for cell in notebook["cells"]:
        if cell["cell_type"] != "code":
            continue
        count += 1
        cell["execution_count"] = count
        cell["outputs"] = _run_cell("".join(cell["source"]), namespace, count)
    if store:
        path.write_text(json.dumps(notebook, indent=1, ensure_ascii=False) + "\n")
    return [c["outputs"] for c in notebook["cells"] if c["cell_type"] == "code"]


def main(argv) -> int:
    import os

    import matplotlib

    matplotlib.use("Agg")
    os.chdir(ROOT)
    sys.path.insert(0, str(ROOT))
    store = "--stdout" not in argv
    names = [a for a in argv if a != "--stdout"]
    for name in names or sorted(p.name for p in HERE.glob("*.ipynb")):
        outputs = execute(HERE / Path(name).name, store)
        if store:
            print(f"stored the outputs of {name}")
        else:
            print(json.dumps(outputs, ensure_ascii=False))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
