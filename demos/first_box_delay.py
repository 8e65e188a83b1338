"""How much later one policy places its first box than another, on the same evaluation seeds.

    python demos/first_box_delay.py NEW.json OLD.json

Both are ``colorsort-eval --json`` files of one variant. For every seed where both placed a box: the time
[s] of the first box placed in its bin; prints the median of NEW minus OLD over those seeds and each run's
mean cycle [s]. A policy that hesitates at the ray (``colorsort-collect --late-pick``) shows as a positive delay.
"""

from __future__ import annotations

import argparse
import json
import statistics
from pathlib import Path


def first_placed(evaluation: dict) -> dict[int, float]:
    """{seed: sim time [s] of its first box placed in the bin of its colour} for the episodes that placed one."""
    return {e["seed"]: min(b["time"] for b in e["boxes"] if b["outcome"] == "placed")
            for e in evaluation["per_episode"] if any(b["outcome"] == "placed" for b in e["boxes"])}


def delay(new: dict, old: dict) -> tuple[float, int]:
    """(median [s] of new's first placed box minus old's over the seeds both placed one, how many seeds)."""
    a, b = first_placed(new), first_placed(old)
    shared = sorted(a.keys() & b.keys())
    if not shared:
        raise ValueError("no evaluation seed where both runs placed a box: give two evaluations of the same seeds")
    return statistics.median(a[s] - b[s] for s in shared), len(shared)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("new", type=Path)
    p.add_argument("old", type=Path)
    args = p.parse_args()
    new, old = json.loads(args.new.read_text()), json.loads(args.old.read_text())
    median, seeds = delay(new, old)
    print(f"first box placed {median:+.2f} s later (median over {seeds} seeds, {new['variant']}); "
          f"mean cycle {new['mean_cycle_time_s']:.2f} s against {old['mean_cycle_time_s']:.2f} s")


if __name__ == "__main__":
    main()
