"""Run the scripted expert on the cell until N boxes have left the belt, and report per box.

Example::

    colorsort-sort --preset default --robot IRB140 --boxes 10 --seed 0 \\
        --video outputs/sort.mp4 --json outputs/sort.json

prints one line per box (colour seen, true colour, bin, cycle time) and a summary (correct,
misplaced, dropped, rejected, boxes per minute of sim time); ``--video`` films the scene camera
with an overlay (phase, colour seen, bin counts) and writes a contact sheet of it beside it
(same name, ``.png``); ``--json`` writes the summary. Exit status 0
when it ran, whatever the score; 2 for bad arguments.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from tqdm import tqdm

from colorsort.benchmark.sorting import SortConfig, run_sort
from colorsort.cli.run import guarded
from colorsort.config import PRESETS
from colorsort.logs import quiet_robosuite_info
from colorsort.robots import ROBOTS


def parse_args(argv: list[str] | None) -> SortConfig:
    parser = argparse.ArgumentParser(prog="colorsort-sort", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--preset", default="default", choices=sorted(PRESETS), help="task preset")
    parser.add_argument("--robot", default="IRB140", choices=list(ROBOTS), help="robot arm")
    parser.add_argument("--boxes", type=int, default=10, help="boxes that must leave the belt")
    parser.add_argument("--seed", type=int, default=0, help="the env's seed")
    parser.add_argument("--video", default=None, help="mp4 of the scene camera with an overlay")
    parser.add_argument("--json", default=None, help="write the summary as JSON here")
    args = parser.parse_args(argv)
    return SortConfig(preset=args.preset, robot=args.robot, boxes=args.boxes, seed=args.seed,
                      video=args.video, json=args.json)


@guarded("colorsort-sort")
def main(argv: list[str] | None = None) -> int:
    quiet_robosuite_info()
    config = parse_args(argv)
    report = run_sort(config, progress=True, log=tqdm.write)
    print(f"{config.robot} on '{config.preset}', seed {config.seed}: {len(report.boxes)} boxes in "
          f"{report.sim_time_s:.1f} s of sim time")
    print(f"correct {report.correct}  misplaced {report.misplaced}  dropped {report.dropped}  "
          f"rejected {report.rejected}  boxes/min {report.boxes_per_minute:.1f}")
    print(f"belt stood still {report.belt_stopped_s:.1f} s" + (f"  let go {report.let_go}" if report.let_go else ""))
    if config.json:
        Path(config.json).parent.mkdir(parents=True, exist_ok=True)
        Path(config.json).write_text(json.dumps(report.to_json(), indent=2))
        print(f"summary: {config.json}")
    if config.video:
        print(f"video: {config.video}  contact sheet: {Path(config.video).with_suffix('.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
