"""The walk of one command through the layers: does it go down without climbing back?

Runs ``nhham <command> <scene> --json`` in this process under a profiler hook that sees
every call from one nhham function to another, and prints

* the layers in the order the walk first enters them;
* every *climb*: a call from a module of a lower layer into a module of a higher one
  (a callback, or a lower layer that calls up), with the caller and the callee.

Layers, lowest first, as ``tests/test_layers.py`` reads them from the imports: system,
lagrangian, hamiltonian, verdict, numerics, cli; the base modules (errors, settings, lazy,
budget) belong to none. Usage::

    python bench/walk.py classify examples/rolling_disk.toml
"""

from __future__ import annotations

import contextlib
import io
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the tree this script is in, not an installed copy

LAYERS = ("system", "lagrangian", "hamiltonian", "verdict", "numerics", "cli")
PACKAGE = str(ROOT / "nhham")


def layer_of(filename: str) -> str | None:
    """The layer of a source file of the package (None outside the layers)."""
    if not filename.startswith(PACKAGE):
        return None
    parts = Path(filename).relative_to(PACKAGE).parts
    return parts[0] if len(parts) > 1 and parts[0] in LAYERS else None


def walk(argv: list[str]) -> tuple[list[str], Counter]:
    """(the collapsed sequence of layers entered, the climbs counted by caller -> callee)."""
    from nhham.cli.main import main

    sequence: list[str] = []
    climbs: Counter = Counter()

    def hook(frame, event, arg):
        if event != "call":
            return
        callee = layer_of(frame.f_code.co_filename)
        caller_frame = frame.f_back
        if callee is None or caller_frame is None:
            return
        caller = layer_of(caller_frame.f_code.co_filename)
        if caller is None:
            return
        if not sequence or sequence[-1] != callee:
            sequence.append(callee)
        if LAYERS.index(callee) > LAYERS.index(caller):
            climbs[(f"{caller}:{caller_frame.f_code.co_name}",
                    f"{callee}:{frame.f_code.co_name}")] += 1

    sys.setprofile(hook)
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            main([*argv, "--json"])
    finally:
        sys.setprofile(None)
    return sequence, climbs


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    sequence, climbs = walk(argv)
    first = list(dict.fromkeys(sequence))
    print(f"nhham {' '.join(argv)}: layers in the order first entered: "
          + " > ".join(first) + f" ({len(sequence)} changes of layer)")
    print(f"climbs (a lower layer calling a higher one): {sum(climbs.values())} calls, "
          f"{len(climbs)} distinct")
    for (caller, callee), count in climbs.most_common():
        print(f"  {caller} -> {callee}  x{count}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
