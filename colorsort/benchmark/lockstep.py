"""Many cells stepped together, one policy call a control step: the evaluator both backends share.

``Cells`` is N worlds stepped in lockstep: the CPU cells (``cpu_cells.CpuCells``: N ColorSort envs in one process,
``colorsort-eval --batch-size N``) or the batched cell on MuJoCo Warp (``batched/evaluate.py``). Each control step
the policy acts on every world's observation at once (``BatchedPolicy``: one forward of a LeRobot checkpoint over
the batch). Two ways to fill the worlds:

- rolling (``run_rolling``), for policies whose only state is a queue of actions refilled for every world at once
  (LeRobot's ACT, and Diffusion Policy on one observation; ``restart_period``): a world whose episode ended starts
  the next episode at the policy's next restart point while the others run on, so a slow episode holds up no other;
- waves (``run_waves``), as LeRobot's ``lerobot-eval`` runs a vector env, for any other policy and for the batched
  cell's films: N worlds start together, the policy is reset once a wave, and a world whose episode ended waits
  for its wave to end (the batched cell steps it on; nothing after its end counts).

An episode is its seed and its held-out shifts (``EpisodePlan``): it starts from them alone, so it is the same whichever
world runs it and when, up to the rounding of a batched forward (a batch of another size sums in another order; a
box may then settle a few steps apart). ``stop()`` turning true (Ctrl-C) starts no new episode; the worlds finish
theirs, and what never started is missing from the results (None).
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from tqdm import tqdm

from colorsort.benchmark.episode_result import EpisodeResult
from colorsort.benchmark.policies import check_policy_spec, checkpoint_cameras
from colorsort.errors import ConfigError

PRECISIONS = ("float32", "bfloat16")  # bfloat16: the forward under CPU autocast; never on unless asked


@dataclass(frozen=True)
class EpisodePlan:
    """One episode to run: its seed and its held-out shifts (``NAME:LEVEL`` texts; none: unshifted)."""

    seed: int
    shift: tuple[str, ...] = ()


class Observations(Protocol):
    """Every world's observation, one row per world: torch tensors (the batched cell's ``StepResult``)."""

    @property
    def state(self) -> Any:
        """(N, state size) float32: observation.state"""

    @property
    def env_state(self) -> Any:
        """(N, 13) float32: observation.environment_state"""

    @property
    def images(self) -> dict:
        """camera -> (N, H, W, 3) uint8 RGB"""


class Cells(Protocol):
    """N worlds stepped together."""

    worlds: int

    def reset(self, episodes: Sequence[EpisodePlan], worlds: np.ndarray) -> Observations:
        """Start ``episodes[i]`` in world ``worlds[i]``; the others carry on."""
        ...

    def step(self, actions: Any, active: np.ndarray) -> Observations:
        """One control step of the ``active`` worlds (the others may be stepped too, uncounted)."""
        ...

    def ended(self) -> np.ndarray:
        """(N,) bool: the world's episode has terminated (its boxes left play, or one went wrong)."""
        ...

    def results(self, worlds: np.ndarray, steps: np.ndarray) -> list[EpisodeResult]:
        """The episodes of ``worlds``, which ended after ``steps`` control steps each."""
        ...


class LockstepPolicy(Protocol):
    """A policy acting on every world at once."""

    name: str
    restart_period: int | None  # steps between points where it holds nothing of any world (None: waves only)

    def reset(self, seed: int) -> None:
        """Before a run or a wave: its generator from ``seed``, its queues emptied."""
        ...

    def begin(self, worlds: np.ndarray, episodes: Sequence[EpisodePlan]) -> None:
        """``worlds`` start ``episodes``: whatever the policy draws for a world comes from that episode's seed."""
        ...

    def act(self, obs: Observations, task: str, active: np.ndarray) -> Any:
        """(N, action size) actions; rows of inactive worlds are not taken."""
        ...


class WaveFilm(Protocol):
    """Films recorded wave by wave (the batched cell's ``films.Filming``)."""

    def start(self) -> None: ...

    def add(self) -> None: ...

    def end(self, results: list[EpisodeResult]) -> None: ...


@dataclass(frozen=True)
class WaveTiming:
    """How long an evaluation took [s], and how many control steps of all worlds it ran."""

    seconds: float
    control_steps: int
    worlds: int


class BatchedPolicy:
    """A LeRobot checkpoint acting on every world at once, on a torch device; or ``random``.

    The forward runs under ``torch.inference_mode`` with images in channels-last order (the convolutions' fast
    layout on the CPU: an (N, H, W, 3) image permuted to (N, 3, H, W) is channels-last already); ``precision``
    ``bfloat16`` runs it under CPU autocast (``PRECISIONS``), never on unless asked.
    """

    def __init__(self, spec: str, device: str, low: np.ndarray, high: np.ndarray, precision: str = "float32"):
        import torch

        check_policy_spec(spec)
        if precision not in PRECISIONS:
            raise ConfigError(f"precision {precision!r}: valid precisions are {list(PRECISIONS)}")
        self.name, self.precision = spec, precision
        self.device = torch.device(device)
        self.low = torch.as_tensor(low, dtype=torch.float32, device=self.device)
        self.high = torch.as_tensor(high, dtype=torch.float32, device=self.device)
        self.policy = None
        if spec == "expert":
            raise ConfigError("the expert reads the sensor camera and plans on the host: evaluate it with "
                              "--backend cpu; the warp backend runs 'random' and LeRobot checkpoints")
        self.cameras: tuple[str, ...] = ()
        self.image_size: tuple[int, int] | None = None
        self.restart_period: int | None = 1
        if spec != "random":
            self.cameras, self.image_size = checkpoint_cameras(spec)
            from colorsort.benchmark.policies import LeRobotPolicy

            loaded = LeRobotPolicy(spec, device=str(self.device))  # in channels-last order where it has cameras
            self.policy = loaded.policy
            self.preprocessor, self.postprocessor = loaded.preprocessor, loaded.postprocessor
            self.restart_period = restart_period(self.policy.config)

    def reset(self, seed: int) -> None:
        import torch

        self.generator = torch.Generator(device=self.device).manual_seed(seed)
        torch.manual_seed(seed)
        self.world_generators: dict[int, Any] = {}
        self.steps = 0  # control steps since the reset: a chunk is predicted every n_action_steps of them
        if self.policy is not None:
            self.policy.reset()

    def begin(self, worlds: np.ndarray, episodes: Sequence[EpisodePlan]) -> None:
        """Each of ``worlds`` draws Diffusion Policy's noise from its episode's seed, as the episode alone would
        (``LeRobotPolicy.reset`` seeds torch with it): the same noise whichever world runs it, whatever the batch."""
        import torch

        for w, e in zip(worlds, episodes, strict=True):
            self.world_generators[int(w)] = torch.Generator(device=self.device).manual_seed(e.seed)

    def act(self, obs: Observations, task: str, active: np.ndarray | None = None) -> Any:
        """Actions (N, action size) for every world's observation."""
        import torch

        n = obs.state.shape[0]
        if self.policy is None:
            u = torch.rand((n, len(self.low)), generator=self.generator, device=self.device)
            return self.low + u * (self.high - self.low)
        batch = {"observation.state": obs.state.to(self.device),
                 "observation.environment_state": obs.env_state.to(self.device), "task": [task] * n}
        for camera, image in obs.images.items():  # as LeRobot's preprocess_observation: (N, 3, H, W) in [0, 1]
            batch[f"observation.images.{camera}"] = image.to(self.device).permute(0, 3, 1, 2).float() / 255.0
        autocast = (torch.autocast(self.device.type, dtype=torch.bfloat16) if self.precision == "bfloat16"
                    else contextlib.nullcontext())
        with torch.inference_mode(), autocast:
            action = self.policy.select_action(self.preprocessor(batch), **self._noise(n))
        self.steps += 1
        return self.postprocessor(action.float())

    def _noise(self, n: int) -> dict[str, Any]:
        """Diffusion Policy's starting noise for the chunk it predicts at this step (every ``n_action_steps`` from
        the reset), each world's from its own generator (``begin``); nothing for a policy that draws none, or
        between chunks."""
        import torch

        assert self.policy is not None
        config = self.policy.config
        if config.type != "diffusion" or self.steps % config.n_action_steps:
            return {}
        shape = (config.horizon, config.action_feature.shape[0])
        idle = torch.Generator(device=self.device).manual_seed(0)  # a world with no episode: never counted
        return {"noise": torch.stack([torch.randn(shape, generator=self.world_generators.get(w, idle),
                                                  device=self.device) for w in range(n)])}


def restart_period(config: Any) -> int | None:
    """Control steps between the points where a LeRobot policy holds no state of any world, or None.

    ACT without temporal ensembling, and Diffusion Policy on one observation, keep nothing between
    steps but their queue of actions, filled for every world at once and emptied every ``n_action_steps``
    steps. At each such point a world may start a new episode and the policy acts on it as on a fresh
    episode (``run_rolling``). Any other state (an ensemble of chunks, a queue of observations) gives None.
    """
    steps = getattr(config, "n_action_steps", None)
    if steps is None or getattr(config, "temporal_ensemble_coeff", None) is not None:
        return None
    return int(steps) if getattr(config, "n_obs_steps", 1) == 1 else None


OnResult = Callable[[int, EpisodeResult], None]  # (the episode's index, its result), as each finishes


def run_waves(cells: Cells, policy: LockstepPolicy, episodes: Sequence[EpisodePlan], max_steps: int, task: str,
              progress: bool = True, film: WaveFilm | None = None, stop: Callable[[], bool] = lambda: False,
              on_result: OnResult | None = None,
              desc: str = "evaluating") -> tuple[list[EpisodeResult | None], WaveTiming]:
    """Every episode, in waves of ``cells.worlds``; results in ``episodes``' order (None: never started, stopped).
    With ``film``, each wave is recorded."""
    n = cells.worlds
    results: list[EpisodeResult | None] = [None] * len(episodes)
    bar = tqdm(total=len(episodes), desc=desc, unit="episode", disable=not progress)
    start, control_steps = time.perf_counter(), 0
    for first in range(0, len(episodes), n):
        if stop():
            break
        wave = list(episodes[first : first + n])
        worlds = np.arange(len(wave))
        obs = cells.reset(wave, worlds)
        policy.reset(wave[0].seed)
        policy.begin(worlds, wave)
        if film is not None:
            film.start()
            film.add()
        active = np.arange(n) < len(wave)
        steps = 0
        while active.any():
            obs = cells.step(policy.act(obs, task, active), active)
            steps += 1
            control_steps += 1
            if film is not None:
                film.add()
            new = np.flatnonzero(active & (cells.ended() | (steps >= max_steps)))
            for w, result in zip(new, cells.results(new, np.full(len(new), steps)), strict=True):
                results[first + int(w)] = result
                if on_result is not None:
                    on_result(first + int(w), result)
            active[new] = False
            bar.update(len(new))
        if film is not None:
            film.end([r for r in results[first : first + len(wave)] if r is not None])
    bar.close()
    return results, WaveTiming(time.perf_counter() - start, control_steps, n)


def run_rolling(cells: Cells, policy: LockstepPolicy, episodes: Sequence[EpisodePlan], max_steps: int, period: int,
                task: str, progress: bool = True, stop: Callable[[], bool] = lambda: False,
                on_result: OnResult | None = None,
                desc: str = "evaluating") -> tuple[list[EpisodeResult | None], WaveTiming]:
    """Every episode, ``cells.worlds`` at a time; a world whose episode ended starts the next one at the policy's
    next restart point (every ``period`` control steps, ``restart_period``) while the others run on. Results in
    ``episodes``' order (None: never started, stopped), each as the episode would be on its own: it starts at a
    restart point, where the policy holds nothing of that world."""
    n = cells.worlds
    episode = np.full(n, -1)  # each world's index into episodes
    start = np.zeros(n, int)  # the control step its episode began at
    active = np.zeros(n, bool)
    upcoming = 0
    results: list[EpisodeResult | None] = [None] * len(episodes)
    bar = tqdm(total=len(episodes), desc=desc, unit="episode", disable=not progress)
    begin, t = time.perf_counter(), 0
    policy.reset(episodes[0].seed if episodes else 0)
    obs: Any = None
    while True:
        if stop():
            upcoming = len(episodes)  # start nothing more; the worlds finish their episodes
        if t % period == 0 and upcoming < len(episodes) and not active.all():
            free = np.flatnonzero(~active)[: len(episodes) - upcoming]
            started = list(episodes[upcoming : upcoming + len(free)])
            obs = cells.reset(started, free)
            policy.begin(free, started)
            episode[free] = np.arange(upcoming, upcoming + len(free))
            start[free], active[free] = t, True
            upcoming += len(free)
        if not active.any() and upcoming >= len(episodes):
            break
        obs = cells.step(policy.act(obs, task, active), active)
        t += 1
        steps = t - start
        ended = np.flatnonzero(active & (cells.ended() | (steps >= max_steps)))
        for w, result in zip(ended, cells.results(ended, steps[ended]), strict=True):
            results[int(episode[w])] = result
            if on_result is not None:
                on_result(int(episode[w]), result)
        active[ended] = False
        bar.update(len(ended))
    bar.close()
    return results, WaveTiming(time.perf_counter() - begin, t, n)
