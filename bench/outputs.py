"""Every example's ``--json`` answers, saved or compared against a saved set.

A refactoring of the exact half must leave the answers alone. This script runs
``nhham classify``, ``derive``, ``compare``, ``linearize`` and ``simulate`` with
``--json`` on every scene in ``examples/`` (one process a command, as a user runs
them; ``--commands`` chooses) and

* ``save DIR``: writes ``DIR/<scene>.<command>.json``;
* ``diff DIR``: runs them again and prints every difference against ``DIR``,
  path by path, ignoring timing fields (keys ending in ``_s`` or named
  ``elapsed``/``timings``); exits 1 when anything differs.

Usage::

    python bench/outputs.py save /tmp/before
    python bench/outputs.py diff /tmp/before          # after the change
    python bench/outputs.py diff /tmp/before --only rolling_disk,snakeboard

The commands run with the default budget; a command that exits non-zero is
recorded with its exit status and envelope, so a refusal is compared too.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = ("classify", "derive", "compare", "linearize", "simulate")
TIMING_KEYS = frozenset({"elapsed", "timings"})


def scenes(only: str | None) -> list[Path]:
    """The scene files of ``examples/``, optionally only those named."""
    found = sorted((ROOT / "examples").glob("*.toml"))
    if only:
        wanted = set(only.split(","))
        found = [p for p in found if p.stem in wanted]
    return found


def run(scene: Path, command: str) -> dict:
    """One command's JSON envelope with its exit status under ``exit_status``."""
    proc = subprocess.run(
        [sys.executable, "-m", "nhham", command, str(scene.relative_to(ROOT)), "--json"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    try:
        envelope = json.loads(proc.stdout)
    except json.JSONDecodeError:
        envelope = {"unparsed_stdout": proc.stdout[-2000:], "stderr": proc.stderr[-2000:]}
    envelope["exit_status"] = proc.returncode
    return envelope


def is_timing(key: str) -> bool:
    """Whether a field is a measured time, which may differ between runs."""
    return key.endswith("_s") or key in TIMING_KEYS


def differences(a: object, b: object, path: str = "") -> Iterator[str]:
    """Every path at which ``a`` and ``b`` differ, timing fields left out."""
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            if is_timing(key):
                continue
            if key not in a or key not in b:
                yield f"{path}/{key}: only in {'after' if key in b else 'before'}"
                continue
            yield from differences(a[key], b[key], f"{path}/{key}")
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            yield f"{path}: length {len(a)} -> {len(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            yield from differences(x, y, f"{path}[{i}]")
    elif a != b:
        yield f"{path}: {str(a)[:120]!r} -> {str(b)[:120]!r}"


def jobs(only: str | None, commands: tuple = COMMANDS) -> list[tuple[Path, str]]:
    return [(scene, command) for scene in scenes(only) for command in commands]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mode", choices=("save", "diff"))
    parser.add_argument("directory", type=Path)
    parser.add_argument("--only", help="comma-separated scene names (file stems)")
    parser.add_argument("--commands", default=",".join(COMMANDS),
                        help="comma-separated commands (default: %(default)s)")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    todo = jobs(args.only, tuple(args.commands.split(",")))
    with ThreadPoolExecutor(args.workers) as pool:
        results = list(pool.map(lambda job: run(*job), todo))
    changed = 0
    for (scene, command), envelope in zip(todo, results):
        name = f"{scene.stem}.{command}.json"
        if args.mode == "save":
            args.directory.mkdir(parents=True, exist_ok=True)
            (args.directory / name).write_text(json.dumps(envelope, indent=1, sort_keys=True))
            print(f"saved {name} (exit {envelope['exit_status']})")
            continue
        saved = args.directory / name
        if not saved.exists():  # a scene added since the outputs were saved
            print(f"new     {name} (exit {envelope['exit_status']})")
            continue
        before = json.loads(saved.read_text())
        found = list(differences(before, envelope))
        changed += bool(found)
        print(f"{'DIFFERS' if found else 'same   '} {name}")
        for line in found[:20]:
            print(f"    {line}")
    if args.mode == "diff":
        print(f"{changed} of {len(todo)} outputs differ")
    return 1 if changed else 0


if __name__ == "__main__":
    raise SystemExit(main())
