"""Shared test helpers (``handmade``, ``paper_reference``) live in this folder.

The tests follow the package tree (``tests/<subpackage>/test_<module>.py``);
this puts the folder on ``sys.path`` so every test can import the helpers,
which are written by hand without nhham.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))


def pytest_configure(config):
    """Compiled libraries go to the test suite's own cache, never to the user's.

    ``.pytest_cache/d/nhham-compiled`` (kept between sessions, so the models are
    compiled once), or a temporary directory without pytest's cache plugin.
    """
    import os
    import tempfile

    cache = getattr(config, "cache", None)
    path = cache.mkdir("nhham-compiled") if cache is not None else tempfile.mkdtemp(
        prefix="nhham-test-cache-")
    os.chmod(path, 0o700)  # the compile cache refuses a directory others may write
    os.environ["NHHAM_CACHE"] = str(path)
