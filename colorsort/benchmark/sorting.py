"""The scripted expert on the cell until N boxes have left the belt, reported per box (``colorsort-sort``).

``run_sort`` returns a ``SortSummary``: counts per outcome, boxes per minute of sim time, the
peak joint speed against the datasheet, and per box the colour seen, the true colour, the bin and
the cycle time; with a video path it films the scene camera with an overlay and writes a contact
sheet beside it.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

from colorsort.cell.referee import Outcome
from colorsort.config import BIN_COLORS, PRESETS, check_range, make_config, sorting_time_limit
from colorsort.data.video import VideoWriter, contact_sheet, draw_lines, save_png
from colorsort.envs.robosuite_task import ColorSort
from colorsort.envs.rollout import CellEpisode, Observer, Step, rollout
from colorsort.errors import UnknownName
from colorsort.expert.base import Expert
from colorsort.expert.factory import make_expert
from colorsort.robots import get_robot

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
            raise UnknownName("preset", self.preset, sorted(PRESETS), "presets")
        get_robot(self.robot)
        check_range("boxes", self.boxes, 1, 10_000)


@dataclass
class SortedBox:
    """One box that left the belt during ``colorsort-sort``."""

    true_color: str
    seen_color: str | None  # None: left the belt before the camera looked at it
    bin: str | None  # None: not placed in a bin
    cycle_time_s: float | None  # [s] from the sensor's detection to the box leaving play (landed, fallen off)


@dataclass
class SortSummary:
    """What ``run_sort`` did: boxes per outcome, rates, the arm's peak speed and every box (``--json``)."""

    correct: int = 0
    misplaced: int = 0
    dropped: int = 0
    rejected: int = 0
    boxes_per_minute: float = 0.0
    sim_time_s: float = 0.0
    peak_speed_ratio: float = 0.0  # max over steps and joints of |joint velocity| / datasheet speed
    belt_stopped_s: float = 0.0  # [s] sim time the belt stood still (0 on a tracking belt)
    let_go: int = 0  # boxes of a bin colour the tracking expert could not meet in time and let ride off
    phase_seconds: dict[str, float] = field(default_factory=dict)  # [s] sim time the expert spent in each phase
    boxes: list[SortedBox] = field(default_factory=list)

    def to_json(self) -> dict:
        return asdict(self)


class SortLog(Observer):
    """``colorsort-sort``'s observer: the time in each of the expert's phases, the belt's stops, the arm's peak
    speed, one line per box that left the belt (``log``), and the filmed overlay."""

    def __init__(self, env: ColorSort, expert: Expert, vmax: np.ndarray, writer: VideoWriter | None,
                 log: Callable[[str], None]):
        self.env, self.expert, self.vmax, self.writer, self.log = env, expert, vmax, writer, log
        self.summary = SortSummary()
        self.handled: dict[int, int] = {}  # box serial -> index of the expert's cycle
        self.reported = 0
        self.thumbs: list[np.ndarray] = []
        self.on_box: Callable[[], None] = lambda: None
        self._cycles_before = 0

    def on_observe(self, obs: dict) -> None:
        self._cycles_before = len(self.expert.cycles)

    def on_action(self, obs: dict, step: Step) -> None:
        expert, env = self.expert, self.env
        if len(expert.cycles) > self._cycles_before:  # the expert looked at a new box: which was it?
            box = _box_at_sensor(env)
            if box is not None:
                self.handled[box] = len(expert.cycles) - 1
        phase = expert.phase.value
        self.summary.phase_seconds[phase] = self.summary.phase_seconds.get(phase, 0.0) + env.control_timestep

    def on_step(self, obs: dict, info: dict) -> None:
        env, report = self.env, self.summary
        report.belt_stopped_s += 0.0 if info["belt_running"] else env.control_timestep
        speed = float(np.max(np.abs(obs["robot0_joint_vel"]) / self.vmax))
        report.peak_speed_ratio = max(report.peak_speed_ratio, speed)
        if self.writer is not None:
            frame = _overlay(obs["scene_image"], self.expert, env)
            self.writer.write(frame)
            if env.timestep % 4 == 1:
                h, w = frame.shape[:2]
                self.thumbs.append(cv2.resize(frame, (SHEET_TILE_WIDTH, h * SHEET_TILE_WIDTH // w),
                                              interpolation=cv2.INTER_AREA))
        for event in env.events[self.reported:]:
            cycle = self.expert.cycles[self.handled[event.serial]] if event.serial in self.handled else None
            cycle_time = None if cycle is None else event.time - cycle.detected_at
            entry = SortedBox(event.color, cycle.seen_color if cycle else None, event.bin, cycle_time)
            report.boxes.append(entry)
            setattr(report, _counter(event.outcome), getattr(report, _counter(event.outcome)) + 1)
            n = len(report.boxes)
            took = f"{cycle_time:5.2f} s" if cycle_time is not None else "    -  "
            self.log(f"box {n:3d}: seen {str(entry.seen_color):8s} true {entry.true_color:7s} "
                     f"-> {str(entry.bin) + ' bin' if entry.bin else event.outcome:10s} cycle {took}")
            self.on_box()
        self.reported = len(env.events)


def run_sort(config: SortConfig, progress: bool = True, log=print) -> SortSummary:
    """Run the expert as ``config`` says and return the report; ``log`` gets one line per box."""
    task = make_config(config.preset)
    limit = sorting_time_limit(config.boxes, task)
    h, w = config.video_size
    env = ColorSort(robots=config.robot, preset=config.preset, use_camera_obs=bool(config.video), camera_names="scene",
                    camera_heights=h, camera_widths=w, ignore_done=True, seed=config.seed, time_limit=limit)
    obs = env.reset()
    expert = make_expert(env)
    expert.reset(obs)
    writer = VideoWriter(config.video, fps=env.control_freq) if config.video else None
    sort_log = SortLog(env, expert, np.array(get_robot(config.robot).joint_speeds), writer, log)
    bar = tqdm(total=config.boxes, unit="box", disable=not progress, desc="sorting")
    sort_log.on_box = lambda: bar.update(1)
    try:
        rollout(CellEpisode(env, config.boxes, limit), obs, expert.act, [sort_log])
    finally:
        bar.close()
        if writer is not None:
            writer.close()
            if sort_log.thumbs and config.video:
                save_png(Path(config.video).with_suffix(".png"), contact_sheet(sort_log.thumbs))
        env.close()
    report = sort_log.summary
    report.let_go = getattr(expert, "let_go", 0)
    report.sim_time_s = env.events[-1].time if len(env.events) >= config.boxes else env.cur_time
    report.boxes_per_minute = 60.0 * len(report.boxes) / report.sim_time_s if report.sim_time_s > 0 else 0.0
    return report


def _counter(outcome: Outcome) -> str:
    """The ``SortSummary`` field that counts ``outcome``."""
    return "correct" if outcome is Outcome.PLACED else outcome.value


def _box_at_sensor(env: ColorSort) -> int | None:
    """Serial of the in-play box nearest the pick point (ground truth, for the report only)."""
    px, py, _ = env.layout.pick_point
    boxes = env.boxes_in_play()
    if not boxes:
        return None
    box = min(boxes, key=lambda b: np.hypot(*(env.box_pos(b)[:2] - (px, py))))
    return box.serial


def _overlay(frame: np.ndarray, expert: Expert, env: ColorSort) -> np.ndarray:
    """The frame with the expert's phase, the colour it saw and the bins' counts written on it."""
    counts = env.task_info()["bins"]
    return draw_lines(frame, [
        f"t {env.cur_time:6.1f} s  phase: {expert.phase.value}",
        f"seen: {expert.seen_color or '-'}",
        "bins: " + "  ".join(f"{c} {counts[c]['count']}" for c in BIN_COLORS),
    ])
