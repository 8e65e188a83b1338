"""Replay a recorded episode from its stored states and actions, and check both (``colorsort-replay``).

*State replay* (``state_replay``) restores each frame's ``sim_state``, checks that it gives back
the recorded observations exactly, and re-renders a camera; ``replay`` compares those frames with
the dataset's decoded video when the camera was recorded at that size. *Action replay*
(``action_replay``) restores the first state and steps the recorded actions: the episode must be
judged a success again (``referee.judge``), through the same states.
"""
from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm import tqdm

from colorsort.cell import sim_state
from colorsort.cell.cameras import CAMERAS
from colorsort.cell.referee import judge
from colorsort.data.config import CollectConfig
from colorsort.data.store import MARKER
from colorsort.data.video import VideoWriter, contact_sheet, save_png
from colorsort.envs.robosuite_task import ColorSort
from colorsort.envs.schema import ACTION, ENV_STATE, SIM_STATE, STATE, box_state, image_key, robot_state
from colorsort.errors import ConfigError, UnknownName

# re-rendered vs decoded frames, worst frame: measured 26.6 dB at 64 px, 29.1 dB at 128 px (h264, crf 30)
MIN_PSNR_DB = 24.0


@dataclass(frozen=True)
class RecordedEpisode:
    """One episode's stored states and actions, and where its frames are."""

    root: Path
    index: int
    settings: dict  # the collector's settings (meta/colorsort.json)
    states: np.ndarray  # (T, S) float64
    actions: np.ndarray  # (T, A) float32
    robot_states: np.ndarray  # (T, 2n + 11) float32, (T, 2n + 12) on a tracking belt: observation.state
    box_states: np.ndarray  # (T, 13) float32: observation.environment_state
    task: str

    @property
    def fps(self) -> int:
        return int(self.settings["fps"])


def load_episode(root: str | Path, index: int, repo_id: str | None = None) -> RecordedEpisode:
    """Read episode ``index`` of the ColorSort dataset at ``root`` (offline)."""
    root = Path(root)
    marker_path = root / MARKER
    if not marker_path.is_file():
        raise ConfigError(not_replayable(root))
    marker = json.loads(marker_path.read_text())
    settings, layout = marker["settings"], marker.get("sim_state")  # no layout: recorded before it was stored
    if layout is not None and layout["version"] != sim_state.VERSION:
        raise ConfigError(f"{root} stores sim_state version {layout['version']}; this ColorSort reads version "
                         f"{sim_state.VERSION}: replay it with the ColorSort that recorded it")
    meta = _metadata(repo_id or settings["repo_id"], root)
    if not 0 <= index < meta.total_episodes:
        raise ConfigError(f"episode {index} does not exist; valid episodes: 0..{meta.total_episodes - 1}")
    ds = _episode_frames(root, meta, index)
    return RecordedEpisode(root, index, settings, np.stack(ds[SIM_STATE]).astype(np.float64),
                           np.stack(ds[ACTION]).astype(np.float32), np.stack(ds[STATE]).astype(np.float32),
                           np.stack(ds[ENV_STATE]).astype(np.float32), meta.episodes[index]["tasks"][0])


def not_replayable(root: Path) -> str:
    """Why the folder ``root`` (with no ColorSort marker) cannot be replayed, and what opens it instead."""
    info = root / "meta" / "info.json"
    if info.is_file() and "next.success" in json.loads(info.read_text()).get("features", {}):
        return (f"{root} is a LeRobot evaluation recording (lerobot-eval --eval.recording=true): it holds the "
                "policy's observations, actions, rewards and success, but not the simulator states that "
                "colorsort-replay restores and re-renders, nor the episodes' seeds. Watch it with "
                f"lerobot-dataset-viz --repo-id local/eval --root {root} --episode-index 0 --save 1 "
                "--output-dir outputs/viz (the viz extra), or film an evaluation with colorsort-eval --report DIR")
    if info.is_file():
        return (f"{root} is a LeRobot dataset but not one colorsort-collect recorded (no {MARKER}): it has no "
                "simulator states to replay; lerobot-dataset-viz shows its frames")
    inside = sorted(found.parent.parent.name for found in root.glob("*/meta/info.json"))
    if inside:
        return f"{root} holds no dataset itself; the datasets under it: {inside}"
    return f"{root} is not a ColorSort dataset (no {MARKER})"


def _metadata(repo_id: str, root: Path):
    """LeRobot's metadata of the dataset at ``root``, without datasets' note that progress bars stay off
    (``HF_DATASETS_DISABLE_PROGRESS_BARS``, which the collector sets)."""
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Cannot enable progress bars")
        return LeRobotDatasetMetadata(repo_id, root=root)


def _episode_frames(root: Path, meta, index: int) -> dict:
    import pyarrow.parquet as pq

    ep = meta.episodes[index]
    path = root / meta.data_path.format(chunk_index=ep["data/chunk_index"], file_index=ep["data/file_index"])
    columns = (SIM_STATE, ACTION, STATE, ENV_STATE)
    table = pq.read_table(path, columns=["episode_index", *columns])
    rows = np.flatnonzero(table.column("episode_index").to_numpy() == index)
    return {k: table.column(k).take(rows).to_pylist() for k in columns}


def recorded_frames(episode: RecordedEpisode, camera: str) -> np.ndarray:
    """The dataset's frames of ``camera`` for this episode, decoded: (T, H, W, 3) uint8."""
    import av
    from lerobot.datasets.video_utils import decode_video_frames

    av.logging.set_libav_level(av.logging.ERROR)

    meta = _metadata(episode.settings["repo_id"], episode.root)
    key = image_key(camera)
    start = meta.episodes[episode.index][f"videos/{key}/from_timestamp"]
    stamps = [start + k / episode.fps for k in range(len(episode.states))]
    frames = decode_video_frames(episode.root / meta.get_video_file_path(episode.index, key), stamps,
                                 tolerance_s=0.5 / episode.fps, backend="pyav")
    return (frames.permute(0, 2, 3, 1).numpy() * 255.0).round().astype(np.uint8)


def make_replay_env(episode: RecordedEpisode) -> ColorSort:
    s = episode.settings
    # datasets recorded before variants were recordable have none
    task = CollectConfig(preset=s["preset"], robot=s["robot"], variant=s.get("variant")).task_config
    return ColorSort(robots=s["robot"], config=task, use_camera_obs=False, has_offscreen_renderer=True,
                     control_freq=s["fps"], ignore_done=True)


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    """Peak signal-to-noise ratio [dB] of two uint8 images."""
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float("inf") if mse == 0 else 10.0 * np.log10(255.0**2 / mse)


@dataclass
class ReplayCheck:
    """What ``replay`` found: the dataset's episode restored frame by frame and replayed from its actions."""

    frames: int
    video: str | None
    sheet: str | None
    state_mismatches: int  # frames whose restored state does not give back the recorded observation state
    min_psnr_db: float | None  # None: the camera was not recorded at this size
    mean_abs_error: float | None  # [0-255 levels]
    outcomes: list[str]  # of the boxes that left the belt in the action replay
    max_state_error: float  # max |replayed - recorded| over the MuJoCo qpos of every frame
    action_replay_ok: bool  # the action replay's episode succeeded (``referee.judge``)

    @property
    def state_replay_ok(self) -> bool:
        return self.state_mismatches == 0 and (self.min_psnr_db is None or self.min_psnr_db >= MIN_PSNR_DB)


def state_replay(env: ColorSort, episode: RecordedEpisode, camera: str, size: tuple[int, int],
                 video: str | None = None, progress: bool = True) -> tuple[np.ndarray, int]:
    """Render ``camera`` at ``size`` (height, width) for every recorded state.

    Returns the frames (T, H, W, 3) uint8 and the number of frames whose restored state did not
    give back the recorded ``observation.state`` and ``observation.environment_state`` exactly.
    """
    h, w = size
    frames = np.empty((len(episode.states), h, w, 3), np.uint8)
    mismatches = 0
    writer = VideoWriter(video, fps=episode.fps) if video else None
    try:
        for k, state in enumerate(tqdm(episode.states, desc="rendering", unit="frame", disable=not progress)):
            env.set_sim_state(state)
            obs = env.observe()
            mismatches += int(not (np.array_equal(robot_state(env, obs), episode.robot_states[k])
                                   and np.array_equal(box_state(env), episode.box_states[k])))
            frames[k] = env.camera_image(camera, w, h)
            if writer is not None:
                writer.write(frames[k])
    finally:
        if writer is not None:
            writer.close()
    return frames, mismatches


def action_replay(env: ColorSort, episode: RecordedEpisode) -> tuple[list[str], bool, float]:
    """Step the recorded actions from the first recorded state; returns the boxes' outcomes, whether
    the episode succeeded, and the largest deviation of the replayed qpos from the recorded one."""
    env.reset()
    env.set_sim_state(episode.states[0])
    nq = env.sim.model.nq
    worst = 0.0
    for k, action in enumerate(episode.actions):
        if k > 0:
            worst = max(worst, float(np.max(np.abs(env.get_sim_state()[1 : 1 + nq] - episode.states[k][1 : 1 + nq]))))
        env.step(action)
    boxes = episode.settings["boxes_per_episode"]
    return [str(e.outcome) for e in env.events[:boxes]], judge(env.events, boxes).success, worst


def replay(root: str | Path, index: int, camera: str = "scene", size: tuple[int, int] | None = None,
           video: str | None = None, sheet: str | None = None, progress: bool = True) -> ReplayCheck:
    """State replay (render, compare) and action replay of one episode, as the module docstring says."""
    if camera not in CAMERAS:
        raise UnknownName("camera", camera, list(CAMERAS), "cameras")
    episode = load_episode(root, index)
    recorded_size = tuple(episode.settings["image_size"])
    size = tuple(size or recorded_size)
    env = make_replay_env(episode)
    try:
        frames, mismatches = state_replay(env, episode, camera, size, video, progress)
        min_psnr = mae = None
        if camera in episode.settings["cameras"] and size == recorded_size:
            reference = recorded_frames(episode, camera)
            min_psnr = min(psnr(a, b) for a, b in zip(frames, reference, strict=False))
            mae = float(np.mean(np.abs(frames.astype(np.int16) - reference.astype(np.int16))))
        if sheet:
            save_png(sheet, contact_sheet(list(frames), fps=episode.fps))
        outcomes, ok, state_error = action_replay(env, episode)
    finally:
        env.close()
    return ReplayCheck(len(frames), video, sheet, mismatches, min_psnr, mae, outcomes, state_error, ok)
