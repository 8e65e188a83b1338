"""Evaluate a policy on a benchmark variant: episodes by seed, on one or more processes.

Episode ``k`` runs with the variant's ``k``-th evaluation seed (or ``seed + k``), so the same call
gives the same numbers, whatever ``envs`` (episodes run at once, one process each). The metrics are
``metrics.py``'s; the command line is ``colorsort-eval`` (``cli/eval.py``).
"""
from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass

from tqdm import tqdm

from colorsort.benchmark.gym_env import ColorSortGymEnv
from colorsort.benchmark.metrics import EvalReport, aggregate
from colorsort.benchmark.policies import check_policy_spec, checkpoint_cameras, make_policy
from colorsort.cell.cameras import parse_cameras
from colorsort.logs import quiet_robosuite_info
from colorsort.variants import Variant, get_variant


def episode_seeds(variant: Variant, episodes: int, seed: int | None) -> list[int]:
    if seed is not None:
        return [seed + k for k in range(episodes)]
    if episodes > len(variant.seeds):
        raise ValueError(f"variant {variant.name!r} has {len(variant.seeds)} evaluation seeds; "
                         f"for {episodes} episodes pass --seed S (seeds S..S+{episodes - 1})")
    return list(variant.seeds[:episodes])


@dataclass(frozen=True)
class EvalSettings:
    """What every evaluation episode shares; each worker process builds its env and policy from it."""

    policy: str
    variant: str
    image_size: tuple[int, int] = (128, 128)  # (height, width) [px]
    cameras: tuple[str, ...] = ("scene", "wrist")
    episode_length: int | None = None  # steps before truncation; None: the variant's time limit


class _Runner:
    """One env and one policy, built once per process, running episodes by seed."""

    def __init__(self, settings: EvalSettings):
        self.policy = make_policy(settings.policy)
        self.env = ColorSortGymEnv(get_variant(settings.variant), cameras=settings.cameras,
                                   image_size=settings.image_size, episode_length=settings.episode_length,
                                   render_mode=None)

    def episode(self, seed: int) -> dict:
        obs, info = self.env.reset(seed=seed)
        self.policy.reset(self.env, seed)
        terminated = truncated = False
        while not (terminated or truncated):
            obs, _, terminated, truncated, info = self.env.step(self.policy.act(obs))
        return {"seed": seed, "success": bool(info["is_success"]), "steps": self.env.steps,
                **{k: info[k] for k in ("correct", "misplaced", "dropped", "let_through", "distractors", "sim_time",
                                        "sorted_times")}}


_runner: _Runner | None = None  # the worker process's own, built by _init_worker


def _init_worker(settings: EvalSettings) -> None:
    global _runner
    quiet_robosuite_info()
    _runner = _Runner(settings)


def _run_episode(seed: int) -> dict:
    return _runner.episode(seed)


def run_episodes(settings: EvalSettings, seeds: list[int], envs: int = 1, progress: bool = True) -> list[dict]:
    """Run one episode per seed, on ``envs`` worker processes (each with its own env and policy).

    Episodes are independent (each starts from its seed), so the results, returned in seed order,
    are the same whatever ``envs``. Workers start with the ``forkserver`` context: no GL context
    or policy state crosses a fork.
    """
    bar = tqdm(total=len(seeds), desc=f"{settings.policy} on {settings.variant}", unit="episode",
               disable=not progress)
    try:
        if envs == 1:
            runner = _Runner(settings)
            results = []
            try:
                for s in seeds:
                    results.append(runner.episode(s))
                    bar.update()
            finally:
                runner.env.close()
            return results
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(["colorsort.benchmark.evaluate"])  # workers fork from a server that imported it once
        with ProcessPoolExecutor(max_workers=envs, mp_context=context, initializer=_init_worker,
                                 initargs=(settings,)) as pool:
            futures = [pool.submit(_run_episode, s) for s in seeds]
            for _ in as_completed(futures):
                bar.update()
            return [f.result() for f in futures]
    finally:
        bar.close()


def evaluate(policy_spec: str, variant_name: str, episodes: int, seed: int | None = None,
             image_size: tuple[int, int] = (128, 128), cameras: tuple[str, ...] = ("scene", "wrist"),
             progress: bool = True, episode_length: int | None = None, envs: int = 1) -> EvalReport:
    """Run ``episodes`` episodes of a policy on a variant (on ``envs`` processes) and aggregate the metrics."""
    if envs < 1:
        raise ValueError(f"envs={envs}: give at least 1")
    variant = get_variant(variant_name)
    check_policy_spec(policy_spec)
    seeds = episode_seeds(variant, episodes, seed)
    settings = EvalSettings(policy_spec, variant.name, tuple(image_size), tuple(cameras), episode_length)
    results = run_episodes(settings, seeds, min(envs, len(seeds)), progress)
    return aggregate(str(policy_spec), variant.name, results)


def observation_settings(policy_spec: str, cameras: str | None,
                         image_size: int | None) -> tuple[tuple[str, ...], tuple[int, int]]:
    """The cameras and (height, width) [px] to render for a policy: as given, else as a checkpoint was
    trained (its ``config.json``), else scene and wrist at 128 px.

    Raises:
        ValueError: an unknown policy, or cameras/size other than those the checkpoint takes.
    """
    check_policy_spec(policy_spec)
    given = parse_cameras(cameras) if cameras is not None else None
    size = (image_size, image_size) if image_size is not None else None
    if policy_spec in ("expert", "random"):
        return (given if given is not None else ("scene", "wrist")), size or (128, 128)
    trained, trained_size = checkpoint_cameras(policy_spec)
    if given is not None and set(given) != set(trained):
        raise ValueError(f"{policy_spec} was trained on cameras {list(trained) or 'none'}; got --cameras {cameras}")
    if size is not None and trained_size is not None and size != trained_size:
        raise ValueError(f"{policy_spec} was trained on {trained_size[0]}x{trained_size[1]} images; "
                         f"got --image-size {image_size}")
    return trained, trained_size or size or (128, 128)
