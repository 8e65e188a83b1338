"""N CPU cells in one process, stepped together (``colorsort-eval --batch-size N``): ``lockstep.Cells`` on MuJoCo.

Each world is a ``ColorSortGymEnv`` of its own, built once and reused episode after episode (an episode starts from
its seed and shifts alone, ``lockstep.EpisodePlan``); a step steps the active ones in turn. What the batch buys is the
policy: one forward over N observations costs far less than N forwards (``benchmarks/bench_forward.py``). An
episode's result is ``cpu_episode_result``'s, the one ``evaluate.EpisodeRunner`` writes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from colorsort.benchmark.episode_result import EpisodeResult, box_record
from colorsort.benchmark.filming import EpisodeFilm
from colorsort.benchmark.lockstep import EpisodePlan
from colorsort.cell.plant import Grip
from colorsort.envs.gym_env import ColorSortGymEnv
from colorsort.variants import Variant


def grip_fields(grip: Grip | None) -> tuple[float | None, float | None]:
    """How the cup held a box: ``grip.offset`` [m] off the cup's axis and ``grip.yaw`` [deg] against the cup
    (None, None for a box never sealed)."""
    return (None, None) if grip is None else (grip.offset, grip.yaw)


def cpu_episode_result(env: ColorSortGymEnv, seed: int, steps: int, sim_time: float) -> EpisodeResult:
    """The episode ``env`` just ran (from ``seed``, ``steps`` control steps, ``sim_time`` [s]), judged:
    its figures, how it ended, each box's outcome and pose, and each held-out shift's draws."""
    cell = env.env
    placed = {p.serial: p for p in cell.placements}
    gripped = {g.serial: g for g in cell.grips}  # a box sealed twice: the last seal
    boxes = [box_record(e, placed[e.serial].offset, placed[e.serial].yaw, *grip_fields(gripped.get(e.serial)))
             for e in cell.events[: env.variant.boxes]]
    return EpisodeResult.judged(seed, steps, sim_time, cell.events, env.variant.boxes, boxes, cell.shifts.record)


@dataclass(frozen=True)
class CpuObservations:
    """Every world's last observation as torch tensors (``lockstep.Observations``)."""

    state: Any
    env_state: Any
    images: dict


class CpuCells:
    """``worlds`` ColorSort envs of one variant, stepped together (``lockstep.Cells``).

    Args:
        variant: the variant every world runs.
        worlds: envs in this process.
        cameras, image_size: what each env renders for the policy (``ColorSortGymEnv``'s).
        episode_length: steps before an episode is truncated (None: the variant's time limit).
        film: film each episode (``filming.EpisodeFilm``): its mp4 bytes in its result's ``video``.
    """

    def __init__(self, variant: Variant, worlds: int, cameras: tuple[str, ...], image_size: tuple[int, int],
                 episode_length: int | None = None, film: bool = False):
        self.worlds, self.film = worlds, film
        self.envs = [ColorSortGymEnv(variant, cameras=cameras, image_size=image_size, episode_length=episode_length,
                                     render_mode="rgb_array" if film else None) for _ in range(worlds)]
        self.max_steps = self.envs[0].max_episode_steps
        self.task = self.envs[0].task_description
        self.obs: list[dict[str, Any]] = [{} for _ in range(worlds)]
        self.seeds = np.zeros(worlds, np.int64)
        self._ended = np.zeros(worlds, bool)
        self.films: list[EpisodeFilm | None] = [None] * worlds
        self._fresh: set[int] = set()  # worlds whose film lacks its first frame

    def reset(self, episodes: Sequence[EpisodePlan], worlds: np.ndarray) -> CpuObservations:
        for w, e in zip(worlds, episodes, strict=True):
            env = self.envs[w]
            if env.shift != tuple(e.shift):
                env.set_shift(e.shift)
            self.obs[w], _ = env.reset(seed=e.seed)
            self.seeds[w], self._ended[w] = e.seed, False
            if self.film:
                self._discard(w)
                self.films[w] = EpisodeFilm(env)
                self._fresh.add(int(w))
        return self._observations()

    def step(self, actions: Any, active: np.ndarray) -> CpuObservations:
        actions = np.asarray(actions.cpu() if hasattr(actions, "cpu") else actions, np.float32)
        for w in np.flatnonzero(active):
            if w in self._fresh:  # the reset's frame
                self._add_frame(int(w))
                self._fresh.discard(int(w))
            self.obs[w], _, terminated, truncated, _ = self.envs[w].step(actions[w])
            self._ended[w] = terminated or truncated
            self._add_frame(int(w))
        return self._observations()

    def ended(self) -> np.ndarray:
        return self._ended.copy()

    def results(self, worlds: np.ndarray, steps: np.ndarray) -> list[EpisodeResult]:
        out = []
        for w, n in zip(worlds, steps, strict=True):
            env = self.envs[w]
            result = cpu_episode_result(env, int(self.seeds[w]), int(n), env.env.cur_time)
            film = self.films[w]
            if film is not None:
                result.video, self.films[w] = film.finish(), None
            out.append(result)
        return out

    def close(self) -> None:
        for w in range(self.worlds):
            self._discard(w)
        for env in self.envs:
            env.close()

    def _add_frame(self, w: int) -> None:
        film = self.films[w]
        if film is not None:
            film.add()

    def _discard(self, w: int) -> None:
        film = self.films[w]
        if film is not None:
            film.discard()
            self.films[w] = None

    def _observations(self) -> CpuObservations:
        import torch

        first = self.obs[0]
        blank = {k: np.zeros_like(v) for k, v in first.items() if k != "pixels"}
        rows = [o or blank for o in self.obs]  # a world that never ran: zeros, never counted
        images = {}
        for camera in first.get("pixels", {}):
            images[camera] = torch.from_numpy(np.stack([o["pixels"][camera] if "pixels" in o
                                                        else np.zeros_like(first["pixels"][camera]) for o in rows]))
        return CpuObservations(torch.from_numpy(np.stack([o["agent_pos"] for o in rows]).astype(np.float32)),
                               torch.from_numpy(np.stack([o["environment_state"] for o in rows]).astype(np.float32)),
                               images)
