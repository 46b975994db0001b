"""Shared test helpers (``handmade``, ``paper_reference``) live in this folder.

The tests follow the package tree (``tests/<subpackage>/test_<module>.py``);
this puts the folder on ``sys.path`` so every test can import the helpers,
which are written by hand without nhham.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
