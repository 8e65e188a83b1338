"""Soak: the scripted expert sorting thousands of boxes in one episode, with the process's memory.

    python benchmarks/soak.py [--preset tracking-fast] [--boxes 2000] [--seed 0] [--every 200]

One env, one expert, never reset: boxes spawn, are sorted and bins emptied until ``--boxes`` have left
play. Every ``--every`` boxes it prints the running counts (placed in the right bin, misplaced,
dropped, let go), the sim and wall time, and the resident memory (RSS) of this process; at the end
the totals and the memory at the first and the last report. A leak (growing buffers, renderer
contexts, event lists) shows as RSS climbing report after report.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from colorsort.config import PRESETS
from colorsort.envs.robosuite_task import ColorSort
from colorsort.expert.factory import make_expert
from colorsort.results import recorded


def rss_mb() -> float:
    """Resident memory of this process [MB] (Linux /proc)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--preset", default="tracking-fast", choices=sorted(PRESETS))
    p.add_argument("--boxes", type=int, default=2000)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--every", type=int, default=200, help="boxes between reports")
    args = p.parse_args()

    env = ColorSort(robots="IRB140", preset=args.preset, has_offscreen_renderer=True, use_camera_obs=False,
                    ignore_done=True, seed=args.seed, time_limit=36_000.0)
    obs = env.reset()
    expert = make_expert(env)
    expert.reset(obs)
    start, first_rss = time.perf_counter(), None
    print(f"IRB140 on '{args.preset}', seed {args.seed}, {args.boxes} boxes in one episode")
    print(f"{'boxes':>6} {'placed':>7} {'misplaced':>9} {'dropped':>7} {'let go':>6} {'sim min':>8} {'wall s':>7} "
          f"{'RSS MB':>7}")
    next_report = args.every
    while len(env.events) < args.boxes:
        obs, _, _, _ = env.step(expert.act(obs))
        if len(env.events) >= next_report or len(env.events) >= args.boxes:
            t = env.tally
            rss = rss_mb()
            first_rss = rss if first_rss is None else first_rss
            print(f"{len(env.events):>6} {sum(t.placed.values()):>7} {t.misplaced:>9} {t.dropped:>7} "
                  f"{getattr(expert, 'let_go', 0):>6} {env.cur_time / 60:>8.1f} {time.perf_counter() - start:>7.0f} "
                  f"{rss:>7.0f}")
            next_report += args.every
    t = env.tally
    events = env.events[: args.boxes]
    rate = 60.0 * len(events) / events[-1].time
    print(f"total: {sum(e.outcome == 'placed' and e.bin == e.color for e in events)} of {len(events)} boxes in the "
          f"bin of their colour, {t.misplaced} misplaced, {t.dropped} dropped, {getattr(expert, 'let_go', 0)} let go; "
          f"{rate:.1f} boxes/min of sim time; bins emptied {t.bins_emptied} times")
    print(f"memory: RSS {first_rss:.0f} MB at the first report, {rss_mb():.0f} MB at the end")
    env.close()


if __name__ == "__main__":
    with recorded(__file__):
        main()
