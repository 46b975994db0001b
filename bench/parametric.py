"""Cost of ``nhham classify --parametric``: verdicts for every parameter value.

Scenes (written to a temporary directory):

* ``paper_3_1p``: Example 3.1 with a parameter in front of each term,
  L = (a v1^2 + b v2^2 - c v3^2)/2, phi = v2 + e v3, values a = b = c = e = 1 (the
  paper's point, which lies in the case c = b e^2);
* ``paper_3_2p``: Example 3.2 likewise, L = (a v1^2 + b v2^2 - c v3^2)/2 + d q1^2/2,
  phi = v1 + e v3, values 1 (case c = a e^2, d != 0);
* ``snake_N`` for N = 2, 4: the scene ``examples/make_snake.py N`` writes (m, l = 1).

Each is run as ``nhham classify SCENE --parametric --positive ...`` (masses, inertias and
lengths declared positive), and, beside it, plain ``nhham classify SCENE`` (which now
answers at the scene's values). In this process: CPU seconds of
:func:`nhham.parametric_classification` (median over ``--runs``, sympy's cache cleared
before each run), with the number of cases found. Whole commands: ``farm-bench``
(wall, CPU and peak memory of the process, medians) when it is installed and
``--farm`` is given.

Usage::

    python bench/parametric.py                 # in-process, 3 runs
    python bench/parametric.py --farm          # and whole commands with farm-bench
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from sympy.core.cache import clear_cache

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import nhham  # noqa: E402

PAPER = {
    "paper_3_1p": ('''name = "paper Example 3.1 with parameters"
coordinates = ["q1", "q2", "q3"]
parameters = { a = 1.0, b = 1.0, c = 1.0, e = 1.0 }
lagrangian = "(a*q1_dot**2 + b*q2_dot**2 - c*q3_dot**2)/2"
constraints = ["q2_dot + e*q3_dot"]
''', "a,b,c"),
    "paper_3_2p": ('''name = "paper Example 3.2 with parameters"
coordinates = ["q1", "q2", "q3"]
parameters = { a = 1.0, b = 1.0, c = 1.0, d = 1.0, e = 1.0 }
lagrangian = "(a*q1_dot**2 + b*q2_dot**2 - c*q3_dot**2)/2 + d*q1**2/2"
constraints = ["q1_dot + e*q3_dot"]
''', "a,b,c"),
}


def scenes(directory: Path) -> dict:
    out = {}
    for name, (text, positive) in PAPER.items():
        path = directory / f"{name}.toml"
        path.write_text(text)
        out[name] = (path, positive)
    for N in (2, 4):
        path = directory / f"snake_{N}.toml"
        subprocess.run([sys.executable, str(ROOT / "examples" / "make_snake.py"), str(N),
                        str(path)], check=True, capture_output=True)
        out[f"snake_{N}"] = (path, "m,l")
    return out


def in_process(path, positive, runs):
    scene = nhham.load_scene(path, drop_redundant=True)
    times, pv = [], None
    for _ in range(runs):
        clear_cache()
        t0 = time.process_time()
        pv = nhham.parametric_classification(scene.system, positive=positive.split(","))
        times.append(time.process_time() - t0)
    return statistics.median(times), pv


def farm(args_list, timeout):
    cmd = ["farm-bench", "-n", "3", "--timeout", str(timeout), "--", sys.executable, "-m",
           "nhham", *args_list]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    return proc.stdout.strip() or proc.stderr.strip()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--farm", action="store_true", help="whole commands with farm-bench")
    ap.add_argument("--timeout", type=int, default=300)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        found = scenes(Path(tmp))
        print("| scene | n, m | parametric_classification CPU s (median) | cases | "
              "generic verdict | scene case |")
        print("|---|---|---|---|---|---|")
        for name, (path, positive) in found.items():
            t, pv = in_process(path, positive, args.runs)
            system = nhham.load_scene(path, drop_redundant=True).system
            where = "generic" if pv.scene_case is None else \
                " and ".join(f"{c} = 0" for c in pv.cases[pv.scene_case].conditions)
            print(f"| {name} | {system.n}, {system.m} | {t:.2f} | {len(pv.cases)} | "
                  f"{pv.generic.describe()} | {where} |")
        if args.farm and shutil.which("farm-bench"):
            for name, (path, positive) in found.items():
                for extra in (["--parametric", "--positive", positive], []):
                    label = " ".join(["classify", name + ".toml", *extra])
                    print(f"\n### nhham {label}\n")
                    print(farm(["classify", str(path), *extra], args.timeout))


if __name__ == "__main__":
    main()
