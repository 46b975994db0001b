"""The compile cache: location, and no cached library loaded unless it is verified.

Every check compares against facts established here independently of the cache's code:
SHA-256 digests computed with ``hashlib`` (and ``sha256sum -c`` when installed), owners
and modes read with ``os.stat``, compiler runs counted by a wrapper script. A corrupted
library is shown not to be loaded by a fresh process that would crash if it were (a
library with zeroed bytes made every run die with SIGSEGV before the cache verified).
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import stat
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from nhham.errors import ComputationError
from nhham.numerics.codegen import numeric_model
from nhham.numerics.codegen.build import build_library, c_compiler, compile_c
from nhham.numerics.codegen.emit import generate_sources
from nhham.numerics.codegen.cache import CompileCache, cache_location
from nhham.numerics.model import NumericsWarning
from nhham.settings import __version__

from test_exact_solutions import chaplygin_sleigh, sleigh_state

HAVE_CC = c_compiler() is not None
needs_cc = pytest.mark.skipif(not HAVE_CC, reason="no C compiler on this machine")
ROOT = Path(__file__).resolve().parents[2]
OTHER_UID = 54321  # owns nothing on this machine; only root may give files to it
as_root = pytest.mark.skipif(os.geteuid() != 0, reason="chown to another uid needs root")

SOURCE = "double nhham_test_value(void) { return 42.0; }\n"


def sha256(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def built(cache):
    """(library, record) of the sleigh's model compiled into ``cache``, not loaded (a
    loaded library must not be damaged in place: the process maps its pages)."""
    outcome = build_library(generate_sources(chaplygin_sleigh()), CompileCache.open(cache))
    assert outcome.path is not None, outcome.note
    return Path(outcome.path), Path(outcome.path + ".sha256")


def loaded_library(cache, monkeypatch):
    """A model made on ``cache`` and the digest of the file it loaded, read at load time."""
    from nhham.numerics.kernels import CompiledRHS

    seen = []
    original = CompiledRHS.load.__func__

    def spy(cls, path, layout, extension=False):
        seen.append(sha256(path))
        return original(cls, path, layout, extension)

    monkeypatch.setattr(CompiledRHS, "load", classmethod(spy))
    model = numeric_model(chaplygin_sleigh(), backend="c", cache_dir=str(cache))
    return model, seen


# ---------------------------------------------------------------- location
def test_location_order(monkeypatch, tmp_path):
    monkeypatch.delenv("NHHAM_CACHE", raising=False)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert cache_location() == str(tmp_path / "home" / ".cache" / "nhham")
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/xdg")  # invalid per the XDG spec
    assert cache_location() == str(tmp_path / "home" / ".cache" / "nhham")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_location() == str(tmp_path / "xdg" / "nhham")
    monkeypatch.setenv("NHHAM_CACHE", str(tmp_path / "env"))
    assert cache_location() == str(tmp_path / "env")
    assert cache_location(tmp_path / "arg") == str(tmp_path / "arg")


def test_the_test_suite_uses_its_own_cache():
    """tests/conftest.py points NHHAM_CACHE away from the user's cache."""
    here = Path(cache_location())
    assert here == Path(os.environ["NHHAM_CACHE"])
    assert Path.home() / ".cache" not in here.parents
    assert ".pytest_cache" in here.parts or "nhham-test-cache" in here.name


def test_a_new_cache_directory_is_private(tmp_path):
    cache = CompileCache.open(tmp_path / "new" / "cache")
    assert not cache.private
    assert stat.S_IMODE(os.stat(cache.directory).st_mode) == 0o700


@needs_cc
def test_library_and_record(tmp_path):
    """The record is the library's SHA-256 in ``sha256sum`` format; both are regular
    files of the user, not writable by others; nothing else is left in the cache."""
    library, record = built(tmp_path)
    assert record.read_text() == f"{sha256(library)}  {library.name}\n"
    for path in (library, record):
        st = os.lstat(path)
        assert stat.S_ISREG(st.st_mode) and st.st_uid == os.geteuid()
        assert not st.st_mode & 0o022
    assert sorted(os.listdir(tmp_path)) == sorted([".lock", library.name, record.name])
    if shutil.which("sha256sum"):
        check = subprocess.run(["sha256sum", "-c", record.name], cwd=tmp_path,
                               capture_output=True, text=True)
        assert check.returncode == 0, check.stdout + check.stderr


# -------------------------------------------------- refused cached libraries
def _zero_bytes(path):
    """Zero the second page (code: loading it crashed the process with SIGSEGV)."""
    data = bytearray(Path(path).read_bytes())
    data[4096:8192] = bytes(4096)
    Path(path).write_bytes(bytes(data))


def _truncate(path):
    data = Path(path).read_bytes()
    Path(path).write_bytes(data[:len(data) // 2])


@needs_cc
@pytest.mark.parametrize("damage, reason", [
    (_zero_bytes, "does not match its recorded SHA-256"),
    (_truncate, "does not match its recorded SHA-256"),
    (lambda p: os.unlink(str(p) + ".sha256"), "has no hash record"),
    (lambda p: os.chmod(p, 0o777), "is writable by group or others"),
    (lambda p: os.chmod(str(p) + ".sha256", 0o666), "has a hash record that is writable"),
    (lambda p: Path(str(p) + ".sha256").write_text("0" * 64 + "  other.so\n"),
     "has a malformed hash record"),
])
def test_a_damaged_library_is_rebuilt_not_loaded(tmp_path, monkeypatch, damage, reason):
    library, record = built(tmp_path)
    good = sha256(library)
    damage(library)
    with pytest.warns(NumericsWarning, match=f"{library.name} {reason}.*rebuilt"):
        model, seen = loaded_library(tmp_path, monkeypatch)
    assert model.backend == "c" and Path(model.compiled.path) == library
    assert seen == [good] and sha256(library) == good  # the rebuilt file was loaded
    assert record.read_text().split()[0] == good
    assert not stat.S_IMODE(os.stat(library).st_mode) & 0o022
    y = sleigh_state()
    ref = numeric_model(chaplygin_sleigh(), backend="numpy")
    assert np.allclose(model.rhs(0, y), ref.rhs(0, y), rtol=1e-13, atol=1e-14)


@needs_cc
@as_root
@pytest.mark.parametrize("which", ["library", "record"])
def test_a_foreign_owned_library_is_refused_and_rebuilt(tmp_path, monkeypatch, which):
    library, record = built(tmp_path)
    good = sha256(library)
    os.chown(library if which == "library" else record, OTHER_UID, -1)
    with pytest.warns(NumericsWarning, match=f"owned by uid {OTHER_UID}.*not loaded"):
        model, seen = loaded_library(tmp_path, monkeypatch)
    assert seen == [good]
    assert os.stat(library).st_uid == os.stat(record).st_uid == os.geteuid()


@needs_cc
def test_a_corrupted_library_does_not_crash_a_new_process(tmp_path):
    """Zeroed bytes in a cached library used to kill every later run with SIGSEGV."""
    library, _ = built(tmp_path)
    _zero_bytes(library)
    code = textwrap.dedent("""
        import sys, warnings
        sys.path[:0] = [sys.argv[1], sys.argv[2]]
        warnings.simplefilter("always")
        from test_exact_solutions import chaplygin_sleigh
        from nhham.numerics.codegen import numeric_model
        print(numeric_model(chaplygin_sleigh(), backend="c").backend)
    """)
    proc = subprocess.run([sys.executable, "-c", code, str(ROOT), str(ROOT / "tests/numerics")],
                          env={**os.environ, "NHHAM_CACHE": str(tmp_path)}, cwd=tmp_path,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["c"]
    assert "does not match its recorded SHA-256" in proc.stderr


# ------------------------------------------------------ refused directories
@needs_cc
@pytest.mark.parametrize("problem, reason", [
    ("world-writable", "is writable by group or others"),
    ("foreign", f"is owned by uid {OTHER_UID}"),
    ("file", "cannot be created"),
    ("unwritable", "is not writable"),
])
def test_an_untrusted_cache_directory_is_not_used(tmp_path, monkeypatch, problem, reason):
    """The model still gets compiled code, from a private temporary directory, with a
    warning naming the directory and the reason; nothing is written to, or loaded from,
    the refused directory."""
    refused = tmp_path / "shared"
    refused.mkdir()
    if problem == "world-writable":
        os.chmod(refused, 0o777)
    elif problem == "foreign":
        if os.geteuid() != 0:
            pytest.skip("chown to another uid needs root")
        os.chown(refused, OTHER_UID, -1)
    elif problem == "file":
        refused.rmdir()
        refused.write_text("not a directory")
        refused = refused / "cache"
    else:
        real_access = os.access
        monkeypatch.setattr(os, "access", lambda p, mode: False if str(p) == str(refused)
                            else real_access(p, mode))
    with pytest.warns(NumericsWarning, match=f"compile cache {refused} {reason}.*private"):
        model = numeric_model(chaplygin_sleigh(), backend="c", cache_dir=str(refused))
    assert model.backend == "c"
    assert not Path(model.compiled.path).is_relative_to(tmp_path)
    if refused.is_dir():
        assert os.listdir(refused) == []


def test_stale_build_directories_are_removed(tmp_path):
    """A build directory of a killed process goes an hour later; a recent one stays."""
    old, new = tmp_path / "build-old", tmp_path / "build-new"
    for d in (old, new):
        d.mkdir()
        (d / "model.c").write_text("/* half */")
    hours_ago = time.time() - 7200
    os.utime(old, (hours_ago, hours_ago))
    os.chmod(tmp_path, 0o700)
    CompileCache.open(tmp_path)
    assert not old.exists() and new.exists()


# --------------------------------------------------------- failed builds
def _compiler(tmp_path, body: str) -> Path:
    """A fake C compiler (shell script) that logs each run, then runs ``body``."""
    script = tmp_path / "fake-cc"
    script.write_text(f"#!/bin/sh\necho run >> {tmp_path / 'runs'}\n{body}\n")
    script.chmod(0o755)
    return script


def _runs(tmp_path) -> int:
    log = tmp_path / "runs"
    return len(log.read_text().splitlines()) if log.exists() else 0


def test_a_failure_is_remembered_for_this_version_only(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    monkeypatch.setenv("CC", str(_compiler(tmp_path, 'echo "x.c:1: error: boom" >&2; exit 1')))
    with pytest.raises(ComputationError, match="C compilation failed: x.c:1: error: boom"):
        compile_c(SOURCE, cache)
    [marker] = [p for p in cache.iterdir() if p.name.endswith(".failed")]
    data = json.loads(marker.read_text())
    assert data["nhham_version"] == __version__ and "boom" in data["diagnostics"]
    with pytest.raises(ComputationError, match="remembered in"):
        compile_c(SOURCE, cache)
    assert _runs(tmp_path) == 1  # the second call did not run the compiler
    data["nhham_version"] = "0.0.0-older"
    marker.write_text(json.dumps(data))
    with pytest.raises(ComputationError, match="error: boom$"):
        compile_c(SOURCE, cache)
    assert _runs(tmp_path) == 2  # retried once under this version, and remembered again
    assert json.loads(marker.read_text())["nhham_version"] == __version__


@pytest.mark.parametrize("body, match", [
    ("kill -9 $$", "stopped by signal 9"),
    ('echo "model.so: No space left on device" >&2; exit 1', "No space left on device"),
])
def test_a_killed_compiler_or_a_full_disk_leaves_no_marker(tmp_path, monkeypatch, body, match):
    cache = tmp_path / "cache"
    monkeypatch.setenv("CC", str(_compiler(tmp_path, body)))
    for runs in (1, 2):
        with pytest.raises(ComputationError, match=match):
            compile_c(SOURCE, cache)
        assert _runs(tmp_path) == runs  # tried again each time
    assert sorted(p.name for p in cache.iterdir()) == [".lock"] or sorted(
        p.name for p in cache.iterdir()) == []


@needs_cc
@as_root
def test_a_foreign_failure_marker_is_ignored(tmp_path, monkeypatch):
    """A marker someone else planted cannot stop a build."""
    real = c_compiler()
    monkeypatch.setenv("CC", str(_compiler(tmp_path, f'exec {real} "$@"')))
    cache = tmp_path / "cache"
    library = Path(compile_c(SOURCE, cache))
    library.unlink()
    marker = Path(str(library) + ".failed")
    marker.write_text(json.dumps({"nhham_version": __version__, "message": "planted"}))
    os.chown(marker, OTHER_UID, -1)
    assert Path(compile_c(SOURCE, cache)) == library and _runs(tmp_path) == 2
    assert not marker.exists()


def test_generated_sources_are_kept_verified_and_reused(tmp_path, monkeypatch):
    """A model of a system seen before is loaded from its kept sources (the generator is
    not run); a tampered sources file is refused, named, and generated again."""
    from nhham.numerics.codegen import emit

    system = chaplygin_sleigh()
    first = numeric_model(system, cache_dir=str(tmp_path))
    kept = sorted(p.name for p in tmp_path.glob("sources_*"))
    assert len(kept) == 2 and kept[1] == kept[0] + ".sha256"
    path = tmp_path / kept[0]
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    assert (tmp_path / kept[1]).read_text().split() == [digest, kept[0]]

    def refuse(*args):
        raise AssertionError("sources generated again")

    with monkeypatch.context() as m:
        m.setattr(emit, "_SOURCES", type(emit._SOURCES)())
        m.setattr(emit, "_generate", refuse)
        again = numeric_model(system, cache_dir=str(tmp_path))
    assert again.python_source == first.python_source and again.layout == first.layout
    assert again.c_complex_source == first.c_complex_source != ""
    y = np.array(sleigh_state())
    assert np.array_equal(again.rhs(0.0, y), first.rhs(0.0, y))

    path.write_text(path.read_text().replace("def ", "def  ", 1))
    monkeypatch.setattr(emit, "_SOURCES", type(emit._SOURCES)())
    with pytest.warns(NumericsWarning, match=r"cached sources .*sources_.*\.json does not "
                                             r"match its recorded SHA-256"):
        third = numeric_model(system, cache_dir=str(tmp_path))
    assert third.python_source == first.python_source
