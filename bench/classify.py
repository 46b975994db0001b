"""Classification cost: the constraint algorithm on the paper's examples.

Times :func:`nhham.algorithm.analyze_constraints` on

* the paper's Examples 2.1 (rolling disk, regular), 3.1 (fully undetermined),
  3.2 (three stages, lambda = q1) and 4.1 (rod: holonomic + nonholonomic);
* the rolling disk with a redundant third constraint (dropped by
  ``System(..., drop_redundant=True)``; building the System, where the
  redundancy is found, is timed separately as ``build``);
* the disk and Example 3.2 side by side in one system (two independent blocks),
  against the sum of its parts,

in three decision modes: ``exact`` (exact reduction, float64 sampling only where
the reduction cannot decide), ``float64`` (every rank and vanishing decided at
seeded sample points in float64) and ``mp30`` (sample points in mpmath with 30
digits). ``analysis`` is ``analyze_constraints`` alone (stages, ranks, decisions,
status; what ``nhham classify`` needs); ``full`` adds what is computed on first use
and what ``report()`` prints: the multipliers, the dynamics and the Frobenius test.

Timing rules (as in bench/derive.py): sympy's global cache is cleared before every
timed run, so no run reuses an earlier run's derivatives; figures are medians over
the runs of CPU seconds of this process (``time.process_time``: single-threaded
sympy, meaningful on a shared machine) with the wall-clock median beside them.
``cold`` is the CPU (wall) time of the first full analysis in a fresh interpreter
(after ``import nhham``), which includes one-off costs (lambdify's namespaces).

Scaling (``--scaling``): the commands a user runs, ``nhham classify``, ``nhham
derive`` (implicit form) and ``nhham compare``, as whole processes on the N-link
snake (N = 2, 4, 8, 12, 16, scenes written by ``examples/make_snake.py``), the
rolling disc in 3-D (built from sympy.physics.mechanics bodies,
``tests/rolling_disc_3d.py``) and ``examples/curvilinear_pair.toml`` (n = 6, C
singular, W(q) dense), with wall and CPU seconds (medians) and the peak memory of
each process. Beside them, sympy's ``LagrangesMethod.form_lagranges_equations`` on the
same scene (:func:`nhham.system.mechanics.to_lagranges_method`) against the whole
``nhham classify`` command, each in a fresh process per run and timed after the
imports (CPU s: scene load included on both sides, caches cold): the ``LM / nhham``
column; and the same comparison with the imports counted, a script that loads the
scene and forms Lagrange's equations against the ``nhham classify`` process (the
``LM script / classify`` column).

Usage::

    python bench/classify.py              # 5 runs per cell, with cold starts
    python bench/classify.py --runs 9
    python bench/classify.py --quick      # 1 run, no cold starts
    python bench/classify.py --scaling    # the scaling table (3 runs per cell)
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import sympy as sp
from sympy.core.cache import clear_cache

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from nhham import Policy, System  # noqa: E402
from nhham.lagrangian.analysis import analyze_constraints  # noqa: E402
from nhham.errors import RedundantConstraintError  # noqa: E402

MODES = {
    "exact": dict(policy=Policy()),
    "float64": dict(policy=Policy(exact=False)),
    "mp30": dict(policy=Policy(exact=False, precision=30)),
}
TARGET = 1.0  # seconds: every paper example, full analysis, every mode (issue 3)


# ------------------------------------------------------------------ systems
def lorentz(potential=0):
    q1, q2, q3 = sp.symbols("q1 q2 q3")
    v1, v2, v3 = sp.symbols("q1_dot q2_dot q3_dot")
    return (v1**2 + v2**2 - v3**2) / 2 + potential, (q1, q2, q3), (v1, v2, v3)


def example_2_1():
    return System(["x", "y", "theta", "phi"],
                  "m*(x_dot**2 + y_dot**2)/2 + I1*theta_dot**2/2 + I2*phi_dot**2/2",
                  ["x_dot - R*cos(theta)*phi_dot", "y_dot - R*sin(theta)*phi_dot"],
                  parameters={"m": 1.0, "I1": 0.5, "I2": 0.25, "R": 1.0},
                  name="Example 2.1 rolling disk")


def example_3_1():
    L, q, v = lorentz()
    return System(q, L, [v[1] + v[2]], name="Example 3.1")


def example_3_2():
    L, q, v = lorentz()
    return System(q, L + q[0]**2 / 2, [v[0] + v[2]], name="Example 3.2")


def example_4_1():
    return System(["x1", "x2", "y1", "y2"],
                  "(x1_dot**2 + x2_dot**2 + y1_dot**2 + y2_dot**2)/2 - g*(y1 + y2)",
                  ["(x2 - x1)*(y2_dot + y1_dot) - (x2_dot + x1_dot)*(y2 - y1)"],
                  holonomic=["((x2 - x1)**2 + (y2 - y1)**2 - l**2)/2"],
                  parameters={"g": 9.81, "l": 1.0}, name="Example 4.1 rod")


REDUNDANT_FORMS = [
    # The natural form; System's redundancy check may not name its combination
    # (it needs sin^2 + cos^2 = 1), in which case the written-out form is used.
    "cos(theta)*x_dot + sin(theta)*y_dot - R*phi_dot",
    "cos(theta)*x_dot + sin(theta)*y_dot - R*(cos(theta)**2 + sin(theta)**2)*phi_dot",
]


def redundant_disk():
    last = None
    for third in REDUNDANT_FORMS:
        try:
            return System(["x", "y", "theta", "phi"],
                          "m*(x_dot**2 + y_dot**2)/2 + I1*theta_dot**2/2 + I2*phi_dot**2/2",
                          ["x_dot - R*cos(theta)*phi_dot", "y_dot - R*sin(theta)*phi_dot", third],
                          parameters={"m": 1.0, "I1": 0.5, "I2": 0.25, "R": 1.0},
                          name="redundant disk", drop_redundant=True)
        except RedundantConstraintError as exc:
            last = exc
    raise last


def disk_and_3_2():
    disk, ex = example_2_1(), example_3_2()
    return System(disk.coordinates + ex.coordinates, disk.lagrangian + ex.lagrangian,
                  list(disk.constraints) + list(ex.constraints),
                  parameters=dict(disk.parameter_values), name="disk + Example 3.2")


CASES = {
    "Example 2.1 (disk, regular)": example_2_1,
    "Example 3.1 (undetermined)": example_3_1,
    "Example 3.2 (3 stages)": example_3_2,
    "Example 4.1 (rod, holonomic)": example_4_1,
    "redundant disk (dropped)": redundant_disk,
    "disk + Example 3.2 (2 blocks)": disk_and_3_2,
}
PAPER = ["Example 2.1 (disk, regular)", "Example 3.1 (undetermined)",
         "Example 3.2 (3 stages)", "Example 4.1 (rod, holonomic)"]


# ------------------------------------------------------------------ timing
def timed(fn, runs):
    cpu, wall, out = [], [], None
    for _ in range(runs):
        clear_cache()
        c0, w0 = time.process_time(), time.perf_counter()
        out = fn()
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
    return statistics.median(cpu), statistics.median(wall), out


def _full(system, kw):
    """Everything ``report()`` prints: stages, multipliers, dynamics, integrability."""
    a = analyze_constraints(system, **kw)
    return a.multipliers, a.dynamics, a.integrable


def cold_start(name):
    """CPU and wall time of the first full analysis in a fresh interpreter (exact)."""
    code = (
        "import sys, time; sys.path.insert(0, %r); sys.path.insert(0, %r)\n"
        "import classify as b\n"
        "s = b.CASES[%r]()\n"
        "t, c = time.perf_counter(), time.process_time(); b._full(s, {})\n"
        "print(time.process_time() - c, time.perf_counter() - t)\n"
    ) % (str(Path(__file__).resolve().parents[1]), str(Path(__file__).resolve().parent), name)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    cpu, wall = map(float, out.stdout.strip().splitlines()[-1].split())
    return cpu, wall


# ------------------------------------------------------------------ scaling
ROOT = Path(__file__).resolve().parents[1]
SNAKES = (2, 4, 8, 12, 16)
COMMANDS = {"classify": [], "derive": [], "compare": []}


def _scene_text(system) -> str:
    """A scene file for a System (names, L, constraints, parameter values)."""
    from nhham.system.expressions import to_text

    def quoted(e):
        return '"' + to_text(e) + '"'
    params = ", ".join(f"{p.name} = {float(system.parameter_values[p])!r}"
                       for p in system.parameters)
    return "\n".join([
        f'name = "{system.name}"',
        "coordinates = [" + ", ".join(f'"{q.name}"' for q in system.coordinates) + "]",
        f"parameters = {{ {params} }}",
        f"lagrangian = {quoted(system.lagrangian)}",
        "constraints = [" + ", ".join(quoted(c) for c in system.constraints) + "]",
        "holonomic = [" + ", ".join(quoted(g) for g in system.holonomic) + "]",
    ]) + "\n"


def _scaling_systems(tmp: Path):
    """(label, scene path, System) for the snakes, the 3-D disc and the singular-C pair."""
    sys.path.insert(0, str(ROOT / "tests"))
    from rolling_disc_3d import rolling_disc_3d

    from nhham.system.scene import load_scene

    out = []
    for N in SNAKES:
        path = tmp / f"snake_{N}.toml"
        subprocess.run([sys.executable, str(ROOT / "examples" / "make_snake.py"), str(N),
                        str(path)], check=True, capture_output=True)
        out.append((f"snake N={N} (n={N + 2}, m={N})", path, load_scene(path).system))
    disc, _ = rolling_disc_3d()
    path = tmp / "rolling_disc_3d.toml"
    path.write_text(_scene_text(disc))
    out.append(("3-D rolling disc (n=5, m=2)", path, load_scene(path).system))
    path = ROOT / "examples" / "curvilinear_pair.toml"
    out.append(("curvilinear pair, C singular (n=6, m=2)", path, load_scene(path).system))
    return out


def _run_command(argv, timeout):
    """(wall s, CPU s, peak MB) of one whole process; None on timeout or failure."""
    w0 = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = w0 + timeout
    while True:
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            break
        if time.perf_counter() > deadline:
            proc.kill()
            os.wait4(proc.pid, 0)
            return None
        time.sleep(0.01)
    wall = time.perf_counter() - w0
    if os.waitstatus_to_exitcode(status) != 0:
        return None
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


def _median_command(argv, runs, timeout):
    rows = [_run_command(argv, timeout) for _ in range(runs)]
    if any(r is None for r in rows):
        return None
    return tuple(statistics.median(r[i] for r in rows) for i in range(3))


# Both sides of the comparison in a fresh process each run, timed after the imports
# (process CPU time), caches cold: the nhham side is the whole classify command (scene
# load, the verdict at the parameter values, classes, the JSON written), the
# LagrangesMethod side loads the same scene, builds the model and forms the equations.
AFTER_IMPORTS = {
    "nhham classify": (
        "import contextlib, io, sys, time\n"
        "import networkx, numpy, scipy.linalg  # noqa\n"
        "import importlib\n"
        "from nhham.cli.main import main\n"
        # the modules classify uses, under the names of this tree and of older ones
        "for name in ('nhham.render.results', 'nhham.hamiltonian.classification',\n"
        "             'nhham.hamiltonian.crosscheck', 'nhham.lagrangian.analysis',\n"
        "             'nhham.lagrangian.parametric', 'nhham.lagrangian.exceptional',\n"
        "             'nhham.verdict.values', 'nhham.system.scene'):\n"
        "    try:\n"
        "        importlib.import_module(name)\n"
        "    except ImportError:\n"
        "        pass\n"
        "t = time.process_time()\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    rc = main(['classify', sys.argv[1], '--json'])\n"
        "print(time.process_time() - t if rc == 0 else 'failed')\n"),
    "LM": (
        "import sys, time\n"
        "import sympy.physics.mechanics  # noqa\n"
        "from nhham.system.scene import load_scene\n"
        "from nhham.system.mechanics import to_lagranges_method\n"
        "t = time.process_time()\n"
        "to_lagranges_method(load_scene(sys.argv[1]).system).lm.form_lagranges_equations()\n"
        "print(time.process_time() - t)\n"),
}

LM_SCRIPT = ("import sys\n"
             "from nhham.system.scene import load_scene\n"
             "from nhham.system.mechanics import to_lagranges_method\n"
             "to_lagranges_method(load_scene(sys.argv[1]).system).lm"
             ".form_lagranges_equations()\n")


def _after_imports(which, path, runs, timeout):
    """Median CPU s of ``AFTER_IMPORTS[which]`` on a scene, one fresh process per run."""
    out = []
    for _ in range(runs):
        try:
            proc = subprocess.run([sys.executable, "-c", AFTER_IMPORTS[which], str(path)],
                                  capture_output=True, text=True, timeout=timeout)
            out.append(float(proc.stdout.strip().splitlines()[-1]))
        except (subprocess.TimeoutExpired, ValueError, IndexError):
            return None
    return statistics.median(out)


def scaling(runs: int, timeout: float = 120.0):
    import tempfile

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"# nhham scaling: {platform.python_version()}, sympy {sp.__version__}, "
          f"{os.cpu_count()} CPUs, load average {load:.1f}; whole commands, median of {runs} "
          f"runs: wall s / CPU s / peak MB; after imports (CPU s, a fresh process per run, "
          f"timed after the imports): LM = load the scene, build the LagrangesMethod and "
          f"form_lagranges_equations, nhham = the whole classify command; LM script = a "
          f"process loading the scene and forming Lagrange's equations (CPU s, imports "
          f"included), against the classify command's CPU s")
    header = ["system"] + [f"nhham {c}" for c in COMMANDS] + [
        "LM after imports", "nhham classify after imports", "LM / nhham",
        "LM script", "LM script / classify"]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    with tempfile.TemporaryDirectory() as tmp:
        for label, path, system in _scaling_systems(Path(tmp)):
            cells, timings = [label], {}
            for cmd, extra in COMMANDS.items():
                res = timings[cmd] = _median_command(
                    [sys.executable, "-m", "nhham", cmd, str(path), "--json", *extra], runs,
                    timeout)
                cells.append("> %g s" % timeout if res is None else
                             f"{res[0]:.2f} / {res[1]:.2f} / {res[2]:.0f}")
            classify = timings["classify"]
            lm = _after_imports("LM", path, runs, timeout)
            work = _after_imports("nhham classify", path, runs, timeout)
            # The same comparison as whole processes: a script that loads the scene and
            # forms Lagrange's equations (imports included, as in the nhham command).
            script = _median_command([sys.executable, "-c", LM_SCRIPT, str(path)], runs,
                                     timeout)
            cells += ["-" if lm is None else f"{lm:.2f}", "-" if work is None else f"{work:.2f}",
                      "-" if lm is None or work is None else f"{lm / work:.1f}",
                      "> %g s" % timeout if script is None else f"{script[1]:.2f}",
                      "-" if script is None or classify is None else
                      f"{script[1] / classify[1]:.1f}"]
            print("| " + " | ".join(cells) + " |", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="1 run, no cold starts")
    ap.add_argument("--scaling", action="store_true",
                    help="the scaling table of the commands on the snakes and the 3-D disc")
    args = ap.parse_args(argv)
    if args.scaling:
        return scaling(3 if args.runs == 5 else args.runs)
    runs = 1 if args.quick else args.runs

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"# nhham classify bench: {platform.python_version()}, sympy {sp.__version__}, "
          f"{os.cpu_count()} CPUs, {platform.machine()}, load average {load:.1f}; median of "
          f"{runs} run(s), CPU s (wall s)")
    header = ["case", "build"] + [f"{m}: analysis / full" for m in MODES] + [
        "cold (exact, full)", "status / stages"]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    worst = {}
    parts = {}
    for name, make in CASES.items():
        cpu_b, wall_b, system = timed(make, runs)
        cells = [name, f"{cpu_b:.3f}"]
        result = None
        for mode, kw in MODES.items():
            cpu, wall, res = timed(lambda: analyze_constraints(system, **kw), runs)
            cpu_f, wall_f, _ = timed(lambda: _full(system, kw), runs)
            cells.append(f"{cpu:.3f} / {cpu_f:.3f} ({wall_f:.3f})")
            worst[(name, mode)] = cpu_f
            if mode == "exact":
                result = res
                parts[name] = cpu
        if args.quick:
            cells.append("-")
        else:
            cpu_c, wall_c = cold_start(name)
            cells.append(f"{cpu_c:.3f} ({wall_c:.3f})")
        cells.append(f"{result.status} / {len(result.stages)}"
                     + (f", dropped {', '.join(d.label for d in result.dropped)}"
                        if result.dropped else ""))
        print("| " + " | ".join(cells) + " |")
    both = parts["disk + Example 3.2 (2 blocks)"]
    alone = parts["Example 2.1 (disk, regular)"] + parts["Example 3.2 (3 stages)"]
    print(f"\nblocks: disk + Example 3.2 in one system {both:.3f} s vs the parts "
          f"{alone:.3f} s (ratio {both / alone:.2f})")
    slow = [(k, v) for k, v in worst.items() if k[0] in PAPER and v >= TARGET]
    print("target (every paper example, full analysis, every mode < 1 s CPU): "
          + ("met" if not slow else "MISSED: " + ", ".join(f"{k} {v:.2f}s" for k, v in slow)))


if __name__ == "__main__":
    main()
