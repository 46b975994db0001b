"""Where the example generators (``make_*.py``) put the scene they write."""

import sys
from pathlib import Path


def write_scene(text: str, target: str) -> None:
    """Write a generated scene to the file ``target``, or to stdout when it is ``-``."""
    if target == "-":
        sys.stdout.write(text)
    else:
        Path(target).write_text(text, encoding="utf-8")
