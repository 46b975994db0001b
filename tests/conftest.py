"""Shared test helpers (``handmade``, ``paper_reference``) live in this folder.

The tests follow the package tree (``tests/<subpackage>/test_<module>.py``;
``numerics/codegen``'s modules in ``tests/numerics``). Test modules are imported by
their file name, so where two modules share one the test file of the second has its
package in front: ``tests/cli/test_cli_budget.py`` (``cli/budget.py``),
``tests/verdict/test_verdict_results.py`` (``verdict/results.py``). This conftest puts
the folder on ``sys.path`` so every test can import the helpers, which are written by
hand without nhham.
"""

import sys
from pathlib import Path

import pytest
from hypothesis import settings

sys.path.insert(0, str(Path(__file__).resolve().parent))

# Property tests draw the same examples on every run (a submission's CI must not fail at
# random); HYPOTHESIS_PROFILE=explore draws new ones, to look for bugs on purpose.
settings.register_profile("default", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(__import__("os").environ.get("HYPOTHESIS_PROFILE", "default"))


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
    # The suite compiles about 140 models from a clean checkout; at -O0 a small one takes a
    # quarter of the compiler's CPU time at the default -O2 (0.22 s against 0.85 s), with the
    # same results (no fast-math: IEEE
    # arithmetic either way) and nothing in the suite timing the compiled code. A flag of
    # your own in NHHAM_CFLAGS is kept (NHHAM_CFLAGS=-O2 runs the suite at the default).
    os.environ.setdefault("NHHAM_CFLAGS", "-O0")


@pytest.fixture(scope="session")
def bicycle():
    """(scene, numeric model) of examples/whipple_bicycle.toml, built once (its load and
    compilation take seconds; its linearisation and its sweeps are tested apart)."""
    from nhham.numerics.codegen import numeric_model
    from nhham.system.scene import load_scene

    scene = load_scene(Path(__file__).resolve().parents[1] / "examples" / "whipple_bicycle.toml")
    return scene, numeric_model(scene.system)


@pytest.fixture(scope="session")
def benchmark_bicycle():
    """(scene, numeric model) of examples/whipple_bicycle_benchmark.toml (the bicycle in
    the 25 parameters of Meijaard et al. 2007), built once."""
    from nhham.numerics.codegen import numeric_model
    from nhham.system.scene import load_scene

    scene = load_scene(Path(__file__).resolve().parents[1] / "examples"
                       / "whipple_bicycle_benchmark.toml")
    return scene, numeric_model(scene.system)


@pytest.fixture(scope="session")
def sleigh():
    """The numeric model of the Chaplygin sleigh of tests/numerics/test_exact_solutions.py
    (its closed form there), for the tests of simulate, its loops and drivers."""
    from nhham.numerics.codegen import numeric_model
    from test_exact_solutions import chaplygin_sleigh

    return numeric_model(chaplygin_sleigh())
