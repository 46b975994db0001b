"""``nhham sweep``: the envelope and its schema, the refusals (exit 2 naming the option),
the budget (exit 3, results kept) and a study killed mid-run resumed to the result of an
uninterrupted one."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import numpy as np
import xarray as xr

from nhham.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
BICYCLE = ROOT / "examples" / "whipple_bicycle_benchmark.toml"
DRIVE = ROOT / "examples" / "differential_drive_motors.toml"


def run(capsys, *argv):
    status = main([str(a) for a in argv])
    out = capsys.readouterr()
    return status, out.out, out.err


def test_refusals_name_their_option(capsys, tmp_path):
    out = tmp_path / "x.zarr"
    robot = ROOT / "examples" / "differential_drive.toml"
    for argv, key, fragment in (
            (["--over", "w=0:1"], "--over", "needs a COUNT"),
            (["--over", "nope=0:1:3"], "--over", "'nope' is not a parameter"),
            (["--over", "w=0:1:3", "--rtol", "1e-6"], "--rtol", "only for --what simulate"),
            (["--over", "w=0:1:3", "--along", "d"], "--along", "'d' is not swept"),
            (["--over", "w=0:1:3", "--out", tmp_path / "x.csv"], "--out", ".zarr directory")):
        args = ["sweep", robot, "--what", "linearize", "--out", out, "--workers", "1",
                "--json", *argv]
        status, stdout, err = run(capsys, *args)
        error = json.loads(stdout)["error"]
        assert status == 2 and error["key"] == key and fragment in error["message"], error
    status, stdout, err = run(capsys, "sweep", BICYCLE, "--what", "linearize", "--out", out)
    assert status == 2 and "--over" in err and "Traceback" not in err


def test_out_of_budget_exits_3_and_resume_finishes(capsys, tmp_path, monkeypatch):
    """12 chunks made to take 0.4 s each and a budget of 3 s: the preparation fits (the
    modules imported and the model built once before), some chunks do, the rest is left
    for --resume."""
    import nhham.study.schedule as schedule
    from nhham.study.sweep import sweep

    assert sweep(DRIVE, "simulate", ["c=0.01:0.05:2"], workers=1).complete

    evaluate = schedule.evaluate

    def slow(study, region, *deadline):
        time.sleep(0.4)
        return evaluate(study, region, *deadline)

    out = tmp_path / "drive.zarr"
    args = ["sweep", DRIVE, "--what", "simulate", "--over", "c=0.01:0.05:12", "--out", out,
            "--workers", "1", "--chunk", "1", "--t-end", "5", "--json"]
    with monkeypatch.context() as m:
        m.setattr(schedule, "evaluate", slow)
        status, stdout, err = run(capsys, *args, "--budget", "3")
    envelope = json.loads(stdout)
    assert status == 3 and "continue with --resume" in envelope["error"]["message"], envelope
    assert envelope["result"]["complete"] is False
    first = envelope["result"]["computed"]
    assert 0 < first < 12
    status, stdout, err = run(capsys, *args, "--resume")
    result = json.loads(stdout)["result"]
    assert status == 0 and result["complete"] and result["computed"] == 12 - first
    assert result["summary"]["failed_runs"] == 0
    assert result["summary"]["max_energy_error"] < 1e-7   # the energy balance closes


def _killed_after_six(command, env, store) -> int:
    """Run the study ``command`` and SIGKILL it once six points are done in ``store``:
    the number of points done then."""
    proc = subprocess.Popen(command, cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 120
        while time.time() < deadline and proc.poll() is None:
            time.sleep(0.05)
            try:
                done = int(xr.open_zarr(store, consolidated=False)["done"].sum())
            except Exception:   # the store is being created
                continue
            if done >= 6:
                break
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait()
        assert proc.returncode in (0, -signal.SIGKILL), "the study failed"
    finally:
        if proc.poll() is None:
            proc.kill()
    return int(xr.open_zarr(store, consolidated=False)["done"].sum())


def test_a_study_killed_mid_run_resumes_to_the_uninterrupted_result(tmp_path):
    """SIGKILL while chunks are being computed and written; --resume then computes only
    the chunks not marked done and gives the same arrays as a run that was not killed."""
    killed, whole = tmp_path / "killed.zarr", tmp_path / "whole.zarr"
    args = [sys.executable, "-m", "nhham", "sweep", str(DRIVE), "--what", "simulate",
            "--over", "c=0.01:0.05:24", "--over", "tau=0.5,1", "--chunk", "2",
            "--t-end", "40", "--rtol", "1e-12", "--workers", "1"]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    # on a loaded machine the store can stay unreadable (being written) until the study
    # ends: then the kill came too late, and the study is killed again from scratch
    for attempt in range(3):
        shutil.rmtree(killed, ignore_errors=True)
        partial = _killed_after_six(args + ["--out", str(killed)], env, killed)
        if partial < 48:
            break
    assert 6 <= partial < 48
    resumed = subprocess.run(args + ["--out", str(killed), "--resume", "--json"], cwd=ROOT,
                             env=env, capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    assert json.loads(resumed.stdout)["result"]["computed"] == 48 - partial
    subprocess.run(args + ["--out", str(whole)], cwd=ROOT, env=env, check=True,
                   capture_output=True)
    a = xr.open_zarr(killed, consolidated=False).load()
    b = xr.open_zarr(whole, consolidated=False).load()
    for name in ("final_state", "t_final", "status", "nfev", "energy_error"):
        assert np.array_equal(a[name].values, b[name].values, equal_nan=True), name
    assert bool(a["done"].all())


def test_what_the_study_side_refuses_exits_2_naming_the_option(capsys, tmp_path):
    """Each refused before any model is built, with one line naming the option."""
    robot = ROOT / "examples" / "differential_drive.toml"
    thesis = tmp_path / "thesis.zarr"
    (thesis / "chapters").mkdir(parents=True)
    damaged = tmp_path / "damaged.zarr"
    status, _, _ = run(capsys, "sweep", robot, "--what", "linearize", "--over", "w=4:5:3",
                       "--out", damaged, "--workers", "1")
    assert status == 0
    (damaged / "done" / "zarr.json").unlink()
    out = tmp_path / "x.zarr"
    for argv, key, fragment in (
            (["--over", "w=1e-400:1:3", "--out", out], "--over",
             "'1e-400' is outside the range of double precision"),
            (["--samples", "4", "--over", "w=0:1", "--seed", "-1", "--out", out], "--seed",
             "a non-negative integer"),
            (["--over", "w=0:1:10000000", "--over", "d=0:1:10000000", "--out", out], "--over",
             "at most 10000000 in one study"),
            (["--over", "w=0:1:3", "--out", out, "--workers", "100000"], "--workers",
             "local workers here"),
            (["--over", "w=0:1:3", "--out", out, "--scheduler", "ucx://127.0.0.1:8786"],
             "--scheduler", "ucx:// is not supported"),
            (["--over", "w=0:1:3", "--out", thesis, "--overwrite"], "--out",
             "not a study nhham wrote"),
            (["--over", "w=4:5:3", "--out", damaged, "--resume"], "--resume",
             "cannot be read as a study")):
        status, stdout, err = run(capsys, "sweep", robot, "--what", "linearize", "--json",
                                  *argv)
        error = json.loads(stdout)["error"]
        assert status == 2 and error["key"] == key and fragment in error["message"], error
        assert len(err.strip().splitlines()) <= 1 and "Traceback" not in err
    assert (thesis / "chapters").is_dir()


def test_a_full_disk_exits_3_with_one_line_and_keeps_what_finished(capsys, tmp_path,
                                                                     monkeypatch):
    import errno

    write = xr.Dataset.to_zarr

    def full_after_first_chunk(self, store=None, *args, **kwargs):
        if kwargs.get("region") is not None and "done" in self.data_vars and \
                int(xr.open_zarr(store, consolidated=False)["done"].sum()) >= 21:
            raise OSError(errno.ENOSPC, "No space left on device")
        return write(self, store, *args, **kwargs)

    out = tmp_path / "map.zarr"
    monkeypatch.setattr(xr.Dataset, "to_zarr", full_after_first_chunk)
    status, stdout, err = run(capsys, "sweep", ROOT / "examples" / "differential_drive.toml",
                              "--what", "linearize", "--over", "w=-4.5:5.5:21", "--over",
                              "d=0.02:0.1:5", "--chunk", "21", "--out", out, "--workers", "1")
    assert status == 3
    assert err.strip().splitlines() == [
        f"nhham: could not write the study to {out} (No space left on device); what "
        f"finished before is kept there: free some space and continue with --resume"]
    assert int(xr.open_zarr(out, consolidated=False)["done"].sum()) == 21


def test_the_help_says_what_a_remote_scheduler_can_do(capsys):
    with pytest.raises(SystemExit):
        main(["sweep", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "unpickled in this process" in text and "tls://host:8786" in text


@pytest.mark.parametrize("scheduler, to_group", [("processes", True), ("threads", False)])
def test_ctrl_c_exits_130_at_once_keeping_what_finished(tmp_path, scheduler, to_group):
    # one worker process (each builds its model: the test stays short)
    """SIGINT (to the process group, as a terminal sends it, or to nhham alone) while
    chunks of long runs are computed: exit 130 with one line on stderr, the chunks written
    before kept in the store, no worker process left. The waits are bounded (a hang fails
    the test instead of blocking it)."""
    import psutil

    out = tmp_path / "runs.zarr"
    args = [sys.executable, "-m", "nhham", "sweep", str(DRIVE), "--what", "simulate",
            "--over", "c=0.01:0.05:400", "--chunk", "1", "--t-end", "200", "--rtol", "1e-12",
            "--workers", "1" if scheduler == "processes" else "2", "--scheduler", scheduler,
            "--out", str(out)]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    # SIGINT as at a terminal: a test run started in the background (a shell's `&`) passes
    # SIGINT on ignored, and Python keeps an ignored SIGINT ignored (the study then ends
    # with 0 whatever the test sends)
    proc = subprocess.Popen(args, cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline, done = time.time() + 120, 0
        while time.time() < deadline and proc.poll() is None and done < 1:
            time.sleep(0.05)
            try:
                done = int(xr.open_zarr(out, consolidated=False)["done"].sum())
            except Exception:   # the store is being created
                continue
        assert proc.poll() is None and done >= 1, "no chunk finished, or the study ended"
        children = psutil.Process(proc.pid).children(recursive=True)
        if to_group:
            os.killpg(proc.pid, signal.SIGINT)
        else:
            os.kill(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130, err.decode()[-3000:]
    assert err.decode().splitlines() == ["nhham: interrupted"]
    assert int(xr.open_zarr(out, consolidated=False)["done"].sum()) >= done
    gone = psutil.wait_procs(children, timeout=10)[1]
    assert not gone, f"worker processes left: {gone}"


def test_ctrl_c_while_the_local_cluster_starts_exits_130_leaving_no_worker(tmp_path):
    """Issue 43 item 8: SIGINT to the process group (as a terminal sends Ctrl-C) as soon
    as the first worker process of the local cluster exists (the cluster takes a second
    or more to start: its workers import dask and register). Before, the interrupt was
    ignored until the cluster had started (lost: the study ran to its end, exit 0). Now:
    exit 130 with one line, no process of the command left, nothing at --out; on its
    terminal (a pseudo-terminal here) nhham had said that it was starting the cluster."""
    import pty
    import select

    import psutil

    out = tmp_path / "map.zarr"
    args = [sys.executable, "-m", "nhham", "sweep", str(ROOT / "tests" / "study" / "scenes" /
                                                     "sleigh_drag.toml"),
            "--what", "linearize", "--over", "U=0.3:1.3:40", "--chunk", "1",
            "--scheduler", "processes", "--workers", "2", "--out", str(out)]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    reader, terminal = pty.openpty()
    proc = subprocess.Popen(args, cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
                            stderr=terminal, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    os.close(terminal)
    said = b""

    def read(wait):
        nonlocal said
        while select.select([reader], [], [], wait)[0]:
            try:
                said += os.read(reader, 4096)
            except OSError:   # the command has closed its end
                return

    try:
        deadline = time.time() + 120
        while time.time() < deadline and proc.poll() is None and not any(
                "spawn_main" in " ".join(_command_line(p))
                for p in psutil.Process(proc.pid).children(recursive=True)):
            read(0.02)
        assert proc.poll() is None, "the command ended before its cluster started"
        os.killpg(proc.pid, signal.SIGINT)
        status = proc.wait(timeout=60)
        read(0.2)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        os.close(reader)
    lines = said.decode().replace("\r", "").splitlines()
    assert status == 130, lines
    assert lines[-1] == "nhham: interrupted" and "Traceback" not in said.decode(), said.decode()
    assert "nhham:   start a local Dask cluster of 2 worker processes" in lines
    left = [p for p in psutil.process_iter(["pid"]) if _session(p) == proc.pid]
    assert not psutil.wait_procs(left, timeout=10)[1], f"processes left: {left}"
    assert not out.exists()


def _command_line(process) -> list:
    try:
        return process.cmdline()
    except Exception:   # gone meanwhile, or not ours to read
        return []


def _session(process) -> int | None:
    try:
        return os.getsid(process.pid)
    except OSError:   # gone meanwhile
        return None


def test_the_budget_bounds_connecting_and_plain_tcp_off_this_machine_is_warned_once(capsys,
                                                                                   tmp_path):
    import socket

    robot = ROOT / "examples" / "differential_drive.toml"
    with socket.socket() as s:           # a port where nothing listens
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    common = ["sweep", robot, "--what", "linearize", "--over", "w=0:1:3", "--json",
              "--budget", "1", "--out", tmp_path / "x.zarr"]
    status, stdout, err = run(capsys, *common, "--scheduler", f"tcp://127.0.0.1:{port}")
    envelope = json.loads(stdout)
    assert status == 3 and envelope["error"]["kind"] == "budget"
    assert "while connecting to the scheduler" in envelope["error"]["message"]
    assert envelope["warnings"] == []                 # loopback: nothing to warn about
    # TEST-NET-1 (RFC 5737): not this machine; whatever answers there (nothing, or not a
    # dask scheduler), the one warning is given
    status, stdout, err = run(capsys, *common, "--scheduler", "tcp://192.0.2.1:8786")
    envelope = json.loads(stdout)
    assert status in (2, 3) and envelope["error"]["key"] in (None, "--scheduler")
    assert len(envelope["warnings"]) == 1 and "clear text" in envelope["warnings"][0]


def test_a_refusal_after_the_scene_is_loaded_names_the_scene_in_the_envelope(capsys,
                                                                           tmp_path):
    """--over names no parameter of the scene: exit 2, and the JSON envelope carries the
    scene it refers to (not null)."""
    status = main(["sweep", "examples/rolling_disk.toml", "--what", "classify",
                   "--over", "nothere=0:1:3", "--out", str(tmp_path / "s.zarr"), "--json"])
    env = json.loads(capsys.readouterr().out)
    assert status == 2 and env["error"]["kind"] == "input"
    assert env["scene"] is not None and env["scene"]["name"] == "vertical rolling disk"
