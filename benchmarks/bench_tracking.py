"""Benchmark conveyor tracking side by side with the stopping belt, in one run.

    python benchmarks/bench_tracking.py --seeds 10 --boxes 20 --workers 2

Runs ``colorsort-sort``'s loop (the scripted expert, IRB 140 at its datasheet joint speeds unless
``--robot``) on each preset for seeds 0..seeds-1 and prints one row per preset: boxes correct,
misplaced, dropped, rejected, let go, boxes per minute of sim time (mean, min-max over seeds),
how long the belt stood still, the fastest joint speed seen over its datasheet limit (``v/vmax``,
at the control rate), and where the arm's time went per box handled (sim seconds per
expert phase, summed over seeds and divided by the boxes placed). Counting is ``colorsort-sort``'s:
boxes that left play per minute of sim time up to the last of them.

Targets on ``tracking``: every box in the bin of its colour, none dropped, the belt never stopped,
at least 20 boxes a minute.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

import numpy as np

from colorsort.config import PRESETS
from colorsort.expert.sorter import SorterPhase
from colorsort.expert.tracking import TrackingPhase
from colorsort.results import recorded
from colorsort.robots import ROBOTS

PRESETS_COMPARED = ("default", "tracking", "tracking-fast")
# both experts' phases, in the order of a pick (a name both have is one row)
PHASES = tuple(dict.fromkeys(p.value for phases in (SorterPhase, TrackingPhase) for p in phases))


def run_one(preset: str, robot: str, boxes: int, seed: int) -> tuple[str, int, dict, float]:
    from colorsort.benchmark.sorting import SortConfig, run_sort
    from colorsort.logs import quiet_robosuite_info

    quiet_robosuite_info()
    t0 = time.perf_counter()
    config = SortConfig(preset=preset, robot=robot, boxes=boxes, seed=seed)
    report = run_sort(config, progress=False, log=lambda _: None)
    return preset, seed, report.to_json(), time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--presets", default=",".join(PRESETS_COMPARED), help=f"comma-separated, of {sorted(PRESETS)}")
    parser.add_argument("--robot", default="IRB140", choices=list(ROBOTS))
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0..seeds-1")
    parser.add_argument("--boxes", type=int, default=20, help="boxes per seed")
    parser.add_argument("--workers", type=int, default=2, help="processes")
    args = parser.parse_args()
    presets = args.presets.split(",")
    unknown = [p for p in presets if p not in PRESETS]
    if unknown:
        parser.error(f"unknown preset(s) {unknown}; valid presets: {sorted(PRESETS)}")

    start = time.perf_counter()
    runs: dict[str, list[dict]] = {p: [] for p in presets}
    with ProcessPoolExecutor(max_workers=args.workers, mp_context=get_context("spawn")) as pool:
        futures = [pool.submit(run_one, p, args.robot, args.boxes, s) for p in presets for s in range(args.seeds)]
        for future in futures:
            preset, _, report, _ = future.result()
            runs[preset].append(report)
    wall = time.perf_counter() - start

    print(f"{args.robot}, seeds 0..{args.seeds - 1}, {args.boxes} boxes each "
          f"({wall:.0f} s wall, {args.workers} workers)")
    print("| preset | belt | correct | misplaced | dropped | rejected | let go | boxes/min (min-max) "
          "| belt stood still "
          "| v/vmax |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for preset, reports in runs.items():
        task = PRESETS[preset]
        total = {k: sum(r[k] for r in reports) for k in ("correct", "misplaced", "dropped", "rejected", "let_go")}
        rates = [r["boxes_per_minute"] for r in reports]
        stood = np.mean([r["belt_stopped_s"] / r["sim_time_s"] for r in reports])
        kind = "tracking" if task.tracking else "stopping"
        belt = f"{kind}, {task.belt_speed} m/s, a box every {task.spawn_period} s"
        print(f"| {preset} | {belt} | {total['correct']} | {total['misplaced']} | {total['dropped']} "
              f"| {total['rejected']} "
              f"| {total['let_go']} | {np.mean(rates):.1f} ({np.min(rates):.1f}-{np.max(rates):.1f}) "
              f"| {100 * stood:.0f}% of sim time | {max(r['peak_speed_ratio'] for r in reports):.2f} |")
    print()
    print("where the arm's time goes, sim seconds per box placed:")
    print("| phase | " + " | ".join(runs) + " |")
    print("| --- |" + " --- |" * len(runs))
    per_box = {p: {ph: sum(r["phase_seconds"].get(ph, 0.0) for r in rs) / max(1, sum(r["correct"] for r in rs))
                   for ph in PHASES} for p, rs in runs.items()}
    for phase in PHASES:
        if any(per_box[p][phase] > 0 for p in runs):
            print(f"| {phase} | " + " | ".join(f"{per_box[p][phase]:.2f}" for p in runs) + " |")
    print("| all | " + " | ".join(f"{sum(per_box[p].values()):.2f}" for p in runs) + " |")


if __name__ == "__main__":
    with recorded(__file__):
        main()
