"""Random well-formed scenes through the command, many of them: the exit statuses met.

Draws scenes and command lines from the strategy of the suite's property test
(``well_formed_scenes`` in ``tests/system/test_scene_fuzz.py``, the one home of scene
generation), runs each command in this process as the test does (``nhham.cli.main.main``,
stdout and stderr captured, ``--budget 2`` in every command line) and counts the exit
statuses by command. Unlike the test it does not stop at the first failure: every
example that ends in anything but 0, 2 or 3 with one line saying why (the test's
``check_outcome``) is written to the log with its scene and command line, and the distinct
failures (their last stderr line, numbers and paths masked) are counted at the end.

Usage::

    nice -n 10 python bench/scene_fuzz.py --examples 10000 --log fuzz-failures.txt
    python bench/scene_fuzz.py --examples 200 --seed 7

The suite runs the same property over a few hundred examples (``NHHAM_FUZZ_EXAMPLES``
sets how many: ``NHHAM_FUZZ_EXAMPLES=10000 pytest tests/system/test_scene_fuzz.py``
stops at the first failure, this script counts them all).
"""

from __future__ import annotations

import argparse
import collections
import os
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# The tree this script is in, not an installed copy; the strategy lives with the tests.
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "tests" / "system"))

from hypothesis import HealthCheck, Phase, given, seed, settings  # noqa: E402

import test_scene_fuzz as fuzz  # noqa: E402


def masked(line: str) -> str:
    """A failure's last line with what varies between examples masked (numbers, paths)."""
    line = re.sub(r"/\S+\.toml", "SCENE", line)
    return re.sub(r"-?\d+(\.\d+)?(e[-+]?\d+)?", "N", line)[:160]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=10000)
    parser.add_argument("--seed", type=int, default=20240)
    parser.add_argument("--log", type=Path, default=Path("scene-fuzz-failures.txt"),
                        help="where every failing example is written (scene and command)")
    parser.add_argument("--every", type=int, default=500, help="progress line every N")
    args = parser.parse_args(argv)

    # thousands of random models: compiled into a folder of their own, removed at the
    # end, never into the user's cache (NHHAM_CACHE, when set, is used as it is)
    own_cache = None if os.environ.get("NHHAM_CACHE") else tempfile.mkdtemp(
        prefix="nhham-fuzz-cache-")
    if own_cache:
        os.chmod(own_cache, 0o700)   # the compile cache refuses a folder others may write
        os.environ["NHHAM_CACHE"] = own_cache
    statuses: collections.Counter = collections.Counter()
    failures: collections.Counter = collections.Counter()
    slowest = [0.0, None]
    start = time.perf_counter()
    log = args.log.open("w", encoding="utf-8")

    @seed(args.seed)
    @settings(max_examples=args.examples, deadline=None, phases=[Phase.generate],
              database=None, derandomize=False, suppress_health_check=list(HealthCheck))
    @given(fuzz.well_formed_scenes())
    def run(case):
        began = time.perf_counter()
        with tempfile.TemporaryDirectory() as folder:
            status, out, err = fuzz.run_command(case, Path(folder))
        took = time.perf_counter() - began
        statuses[(case.argv[0], status)] += 1
        if took > slowest[0]:
            slowest[:] = [took, case]
        try:
            fuzz.check_outcome(case, status, out, err)
        except AssertionError:
            last = (err.strip().splitlines() or ["(nothing on stderr)"])[-1]
            failures[masked(last)] += 1
            log.write(f"=== exit {status} ({took:.1f} s)\n{err.strip()[-2000:]}\n{case}\n")
            log.flush()
        done = sum(statuses.values())
        if done % args.every == 0:
            print(f"{done} examples, {time.perf_counter() - start:.0f} s, "
                  f"{sum(failures.values())} failures", flush=True)

    try:
        run()
    finally:
        log.close()
        if own_cache:
            shutil.rmtree(own_cache, ignore_errors=True)
    wall = time.perf_counter() - start
    total = sum(statuses.values())
    commands = sorted({c for c, _ in statuses})
    codes = sorted({s for _, s in statuses})
    print(f"\n{total} examples in {wall:.0f} s ({wall / max(total, 1):.2f} s each), seed "
          f"{args.seed}; slowest {slowest[0]:.1f} s")
    print("command      " + "".join(f"{'exit ' + str(s):>9}" for s in codes))
    for c in commands:
        print(f"{c:<13}" + "".join(f"{statuses[(c, s)]:>9}" for s in codes))
    print(f"\n{sum(failures.values())} failing examples, {len(failures)} distinct "
          f"(written to {args.log}):")
    for line, count in failures.most_common():
        print(f"{count:6}  {line}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
