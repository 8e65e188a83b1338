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
from dataclasses import asdict, dataclass, field
from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

from colorsort.config import BIN_COLORS, PRESETS, ROBOT_JOINT_SPEEDS, ROBOTS, make_config, sorting_time_limit
from colorsort.env import ColorSort
from colorsort.expert import SortingExpert
from colorsort.logs import quiet_robosuite_info
from colorsort.video import VideoWriter, contact_sheet, save_png

SHEET_TILE_WIDTH = 320  # [px] frames kept for the contact sheet are shrunk to this width


@dataclass(frozen=True)
class SortConfig:
    """What to run.

    Attributes:
        preset: task preset ("default", "seed", ...).
        robot: "IRB140", "Panda" or "UR5e".
        boxes: stop once this many boxes have left the belt (placed, misplaced, dropped, rejected).
        seed: the env's seed.
        video: mp4 path for the scene camera, or None.
        video_size: (height, width) of the video [px].
        json: path for the JSON summary, or None.
    """

    preset: str = "default"
    robot: str = "IRB140"
    boxes: int = 10
    seed: int = 0
    video: str | None = None
    video_size: tuple[int, int] = (480, 640)
    json: str | None = None

    def __post_init__(self) -> None:
        if self.preset not in PRESETS:
            raise ValueError(f"Unknown preset {self.preset!r}. Valid presets: {sorted(PRESETS)}")
        if self.robot not in ROBOTS:
            raise ValueError(f"Unknown robot {self.robot!r}. Valid robots: {list(ROBOTS)}")
        if not 1 <= self.boxes <= 10_000:
            raise ValueError(f"boxes={self.boxes} out of range; valid values lie in [1, 10000]")


@dataclass
class BoxReport:
    true_color: str
    seen_color: str | None  # None: left the belt before the camera looked at it
    bin: str | None  # None: not placed in a bin
    cycle_time_s: float | None  # [s] from the sensor's detection to the box leaving play (landed, fallen off)


@dataclass
class SortReport:
    correct: int = 0
    misplaced: int = 0
    dropped: int = 0
    rejected: int = 0
    boxes_per_minute: float = 0.0
    sim_time_s: float = 0.0
    peak_speed_ratio: float = 0.0  # max over steps and joints of |joint velocity| / datasheet speed
    boxes: list[BoxReport] = field(default_factory=list)

    def to_json(self) -> dict:
        return asdict(self)


def run_sort(config: SortConfig, progress: bool = True, log=print) -> SortReport:
    """Run the expert as ``config`` says and return the report; ``log`` gets one line per box."""
    task = make_config(config.preset)
    limit = sorting_time_limit(config.boxes, task)
    h, w = config.video_size
    env = ColorSort(robots=config.robot, preset=config.preset, use_camera_obs=bool(config.video), camera_names="scene",
                    camera_heights=h, camera_widths=w, ignore_done=True, seed=config.seed, time_limit=limit)
    obs = env.reset()
    expert = SortingExpert(env)
    expert.reset(obs)
    writer = VideoWriter(config.video, fps=env.control_freq) if config.video else None
    report = SortReport()
    vmax = np.array(ROBOT_JOINT_SPEEDS[config.robot])
    handled: dict[int, int] = {}  # box serial -> index of the expert's cycle
    reported = 0
    thumbs: list[np.ndarray] = []
    bar = tqdm(total=config.boxes, unit="box", disable=not progress, desc="sorting")
    try:
        while len(env.events) < config.boxes and env.cur_time < limit:
            cycles_before = len(expert.cycles)
            action = expert.act(obs)
            if len(expert.cycles) > cycles_before:  # the expert looked at a new box: which was it?
                box = _box_at_sensor(env)
                if box is not None:
                    handled[box] = len(expert.cycles) - 1
            obs, _, _, _ = env.step(action)
            speed = float(np.max(np.abs(obs["robot0_joint_vel"]) / vmax))
            report.peak_speed_ratio = max(report.peak_speed_ratio, speed)
            if writer is not None:
                frame = _overlay(obs["scene_image"], expert, env)
                writer.write(frame)
                if env.timestep % 4 == 1:
                    h, w = frame.shape[:2]
                    thumbs.append(cv2.resize(frame, (SHEET_TILE_WIDTH, h * SHEET_TILE_WIDTH // w),
                                             interpolation=cv2.INTER_AREA))
            for event in env.events[reported:]:
                cycle = expert.cycles[handled[event.serial]] if event.serial in handled else None
                cycle_time = None if cycle is None else event.time - cycle.detected_at
                entry = BoxReport(event.color, cycle.seen_color if cycle else None, event.bin, cycle_time)
                report.boxes.append(entry)
                setattr(report, _counter(event.outcome), getattr(report, _counter(event.outcome)) + 1)
                n = len(report.boxes)
                took = f"{cycle_time:5.2f} s" if cycle_time is not None else "    -  "
                log(f"box {n:3d}: seen {str(entry.seen_color):8s} true {entry.true_color:7s} "
                    f"-> {str(entry.bin) + ' bin' if entry.bin else event.outcome:10s} cycle {took}")
                bar.update(1)
            reported = len(env.events)
    finally:
        bar.close()
        if writer is not None:
            writer.close()
            if thumbs:
                save_png(Path(config.video).with_suffix(".png"), contact_sheet(thumbs))
        env.close()
    report.sim_time_s = env.events[-1].time if len(env.events) >= config.boxes else env.cur_time
    report.boxes_per_minute = 60.0 * len(report.boxes) / report.sim_time_s if report.sim_time_s > 0 else 0.0
    return report


def _counter(outcome: str) -> str:
    return "correct" if outcome == "placed" else outcome


def _box_at_sensor(env: ColorSort) -> int | None:
    """Serial of the in-play box nearest the pick point (ground truth, for the report only)."""
    px, py, _ = env.layout.pick_point
    boxes = env.boxes_in_play()
    if not boxes:
        return None
    box = min(boxes, key=lambda b: np.hypot(*(env.box_pos(b)[:2] - (px, py))))
    return box.serial


def _overlay(frame: np.ndarray, expert: SortingExpert, env: ColorSort) -> np.ndarray:
    """The frame with the expert's phase, the colour it saw and the bins' counts written on it."""
    out = frame.copy()
    counts = env.task_info()["bins"]
    lines = [
        f"t {env.cur_time:6.1f} s  phase: {expert.phase.value}",
        f"seen: {expert.seen_color or '-'}",
        "bins: " + "  ".join(f"{c} {counts[c]['count']}" for c in BIN_COLORS),
    ]
    scale = out.shape[0] / 480
    for i, text in enumerate(lines):
        org = (int(10 * scale), int((24 + 22 * i) * scale))
        cv2.putText(out, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.6 * scale, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(out, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.6 * scale, (255, 255, 255), 1, cv2.LINE_AA)
    return out


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
    try:
        return SortConfig(preset=args.preset, robot=args.robot, boxes=args.boxes, seed=args.seed,
                          video=args.video, json=args.json)
    except ValueError as err:
        parser.error(str(err))  # exits with status 2
        raise


def main(argv: list[str] | None = None) -> int:
    quiet_robosuite_info()
    config = parse_args(argv)
    report = run_sort(config, progress=True, log=tqdm.write)
    print(f"{config.robot} on '{config.preset}', seed {config.seed}: {len(report.boxes)} boxes in "
          f"{report.sim_time_s:.1f} s of sim time")
    print(f"correct {report.correct}  misplaced {report.misplaced}  dropped {report.dropped}  "
          f"rejected {report.rejected}  boxes/min {report.boxes_per_minute:.1f}")
    if config.json:
        Path(config.json).parent.mkdir(parents=True, exist_ok=True)
        Path(config.json).write_text(json.dumps(report.to_json(), indent=2))
        print(f"summary: {config.json}")
    if config.video:
        print(f"video: {config.video}  contact sheet: {Path(config.video).with_suffix('.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
