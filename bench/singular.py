"""The Dirac–Bergmann chain on the gallery of singular Lagrangians (issue 45).

For each scene of ``examples/singular`` it times ``classify`` (the chain, its classes,
gauge generators and Dirac bracket: the command's journey, scene load included) and
``classify --parametric``, and where the scene has ``[initial]`` and ``[steady]`` tables
``simulate`` (t_end = 10) and ``linearize`` (the motion on M_f), in this process, medians
of ``--runs`` runs after one warm-up, with the ratio to ``classify`` of the vertical
rolling disk (the quick start's scene) timed the same way in the same process, and prints
the answer (generations, first and second class, degrees of freedom) next to the time.
A refused run (a gauge system without ``[gauge]``) shows ``-``.

Usage::

    python bench/singular.py            # every gallery scene, 5 runs
    python bench/singular.py --runs 3 --only proca_mode,yang_mills_su2
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def median_time(fn, runs: int) -> float:
    fn()  # warm-up: imports, caches of sympy
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    from nhham.journeys.simulation import simulate
    from nhham.journeys.stability import linearize
    from nhham.journeys.verdict import classify, classify_parametric
    from nhham.system.scene import load_scene

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--only", help="comma-separated scene stems")
    args = parser.parse_args()
    scenes = sorted((ROOT / "examples" / "singular").glob("*.toml"))
    if args.only:
        keep = set(args.only.split(","))
        scenes = [s for s in scenes if s.stem in keep]
    disk = str(ROOT / "examples" / "rolling_disk.toml")
    base = median_time(lambda: classify(disk), args.runs)
    print(f"baseline: classify rolling_disk.toml {base:.3f} s (median of {args.runs})")
    print("| scene | generations | FC | SC | dof | classify s | / disk | --parametric s "
          "| cases | simulate s | linearize s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for scene in scenes:
        path = str(scene)
        data = classify(path).data
        t = median_time(lambda: classify(path), args.runs)
        tp = median_time(lambda: classify_parametric(path), args.runs)
        cases = len(classify_parametric(path).data["cases"])
        gens = "+".join(str(len(g)) for g in data["generations"])
        loaded = load_scene(path, check_initial=False)
        ts = tl = "-"
        if loaded.initial_given is not None and loaded.gauge is not None:
            ts = _timed(lambda: simulate(load_scene(path, check_initial=False), t_end=10.0),
                        args.runs)
        if loaded.steady is not None:
            tl = _timed(lambda: linearize(load_scene(path, check_initial=False)), args.runs)
        print(f"| {scene.stem} | {gens} | {data['first_class']} | {data['second_class']} | "
              f"{data['degrees_of_freedom']} | {t:.3f} | {t / base:.1f} | {tp:.3f} | {cases} "
              f"| {ts} | {tl} |")


def _timed(fn, runs: int) -> str:
    """The median time as text, ``-`` where the command refuses the scene."""
    from nhham.errors import InputError

    try:
        return f"{median_time(fn, runs):.3f}"
    except InputError:
        return "-"


if __name__ == "__main__":
    main()
