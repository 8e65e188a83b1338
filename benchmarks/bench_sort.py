"""Benchmark the scripted expert: sorting accuracy and throughput over seeds.

    python benchmarks/bench_sort.py --preset default --seeds 10 --boxes 20 --workers 2
    python benchmarks/bench_sort.py --preset seed --seeds 3 --boxes 5

Runs ``colorsort-sort``'s loop for each seed in 0..seeds-1 (IRB 140 at its datasheet joint
speeds unless ``--robot``) and prints per seed: boxes correct, misplaced, dropped, rejected,
boxes per minute of sim time, mean cycle time (sensor detection to the box in its bin) and
the peak joint speed measured at the control rate as a fraction of the datasheet limit.
Targets on ``default``: every box in its colour's bin, none dropped, at least 12 boxes a minute.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

import numpy as np

from colorsort.config import PRESETS
from colorsort.results import recorded
from colorsort.robots import ROBOTS


def run_one(preset: str, robot: str, boxes: int, seed: int) -> tuple[int, dict, float]:
    from colorsort.benchmark.sorting import SortConfig, run_sort

    t0 = time.perf_counter()
    config = SortConfig(preset=preset, robot=robot, boxes=boxes, seed=seed)
    report = run_sort(config, progress=False, log=lambda _: None)
    return seed, report.to_json(), time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--preset", default="default", choices=sorted(PRESETS))
    parser.add_argument("--robot", default="IRB140", choices=list(ROBOTS))
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0..seeds-1")
    parser.add_argument("--boxes", type=int, default=20, help="boxes per seed")
    parser.add_argument("--workers", type=int, default=2, help="processes")
    args = parser.parse_args()

    print(f"{args.robot} on '{args.preset}', {args.boxes} boxes per seed")
    print(f"{'seed':>4} {'correct':>8} {'misplaced':>10} {'dropped':>8} {'rejected':>9} {'boxes/min':>10} "
          f"{'cycle s':>8} {'v/vmax':>7} {'sim s':>7} {'wall s':>7}")
    rows = []
    with ProcessPoolExecutor(max_workers=args.workers, mp_context=get_context("spawn")) as pool:
        futures = [pool.submit(run_one, args.preset, args.robot, args.boxes, s) for s in range(args.seeds)]
        for future in futures:
            seed, r, wall = future.result()
            cycles = [b["cycle_time_s"] for b in r["boxes"] if b["cycle_time_s"] is not None and b["bin"]]
            rows.append((r, cycles))
            print(f"{seed:>4} {r['correct']:>8} {r['misplaced']:>10} {r['dropped']:>8} {r['rejected']:>9} "
                  f"{r['boxes_per_minute']:>10.1f} {np.mean(cycles) if cycles else float('nan'):>8.2f} "
                  f"{r['peak_speed_ratio']:>7.2f} {r['sim_time_s']:>7.1f} {wall:>7.1f}", flush=True)
    total = {k: sum(r[k] for r, _ in rows) for k in ("correct", "misplaced", "dropped", "rejected")}
    rates = [r["boxes_per_minute"] for r, _ in rows]
    all_cycles = [c for _, cs in rows for c in cs]
    print(f"{'all':>4} {total['correct']:>8} {total['misplaced']:>10} {total['dropped']:>8} {total['rejected']:>9} "
          f"{np.mean(rates):>10.1f} {np.mean(all_cycles):>8.2f} {max(r['peak_speed_ratio'] for r, _ in rows):>7.2f}"
          f"   (boxes/min: min {np.min(rates):.1f}, cycle: max {np.max(all_cycles):.2f} s)")


if __name__ == "__main__":
    with recorded(__file__):
        main()
