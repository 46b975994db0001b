"""Building the compiled library (nhham.numerics.codegen.build): built once and found
again in the cache; without Python's headers the plain library, with the failure kept."""

from __future__ import annotations

import os

import numpy as np
import pytest

from nhham.numerics.codegen import c_compiler, numeric_model
from nhham.numerics.model import NumericsWarning

from test_exact_solutions import chaplygin_sleigh, sleigh_state

HAVE_CC = c_compiler() is not None


@pytest.mark.skipif(not HAVE_CC, reason="no C compiler on this machine")
def test_compiled_library_is_cached(tmp_path):
    a = numeric_model(chaplygin_sleigh(), backend="c", cache_dir=str(tmp_path))
    files = sorted(os.listdir(tmp_path))
    b = numeric_model(chaplygin_sleigh(), backend="c", cache_dir=str(tmp_path))
    assert a.backend == b.backend == "c"
    library = os.path.basename(a.compiled.path)
    sources = [f for f in files if f.startswith("sources_")]   # the generated code, kept
    assert len(sources) == 2 and sources[1] == sources[0] + ".sha256"
    assert files == sorted([".lock", library, library + ".sha256", *sources])
    assert sorted(os.listdir(tmp_path)) == files
    assert a.compiled.path == b.compiled.path


@pytest.mark.skipif(not HAVE_CC, reason="no C compiler on this machine")
def test_without_python_headers_the_plain_library_is_used(monkeypatch, tmp_path):
    """When the CPython entry points cannot be built (no Python.h, say), the
    plain ctypes library is built instead, says so, gives the same values, and
    later models with the same source do not try again (the failure is kept in the
    cache, beside where the library would be)."""
    import nhham.numerics.codegen.build as build
    from nhham.numerics.integrate import simulate

    monkeypatch.setattr(build, "pyext_flags",
                        lambda: (["-DNHHAM_PYEXT", "-I/nonexistent-include"], "none"))
    with pytest.warns(NumericsWarning, match="CPython entry points could not be built"):
        model = numeric_model(chaplygin_sleigh(), cache_dir=str(tmp_path))
    assert model.backend == "c" and model.compiled.ext is None
    assert "CPython entry points unavailable" in model.backend_note
    assert [f for f in os.listdir(tmp_path) if f.endswith(".failed")]
    y = sleigh_state()
    ref = numeric_model(chaplygin_sleigh(), backend="numpy")
    assert np.allclose(model.rhs(0, y), ref.rhs(0, y), rtol=1e-13, atol=1e-14)
    res = simulate(model, (0, 1), y, warn=False)
    assert res.settings["loop"] == "compiled" and res.success
    with pytest.warns(NumericsWarning, match="Python.h.*remembered in"):
        again = numeric_model(chaplygin_sleigh(m=2.0), cache_dir=str(tmp_path))
    assert again.compiled.ext is None and "unavailable" in again.backend_note
