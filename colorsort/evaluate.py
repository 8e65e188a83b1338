"""Evaluate a policy on a benchmark variant: success rate with a confidence interval and sorting metrics.

Example::

    colorsort-eval --policy expert --variant default --episodes 50 --envs 2 --json outputs/eval.json
    colorsort-eval --policy outputs/train/act/checkpoints/last/pretrained_model --variant jitter --episodes 20
    colorsort-eval --list

Episode ``k`` runs with the variant's ``k``-th evaluation seed (or ``--seed S`` + k), so the same
command gives the same numbers, whatever ``--envs`` (episodes run at once, one process each).
Metrics: success rate (every box of the episode where it belongs, none misplaced or dropped) with a 95% Wilson interval; boxes placed correctly, misplaced, dropped;
distractors (boxes with no bin) let through; boxes per minute (boxes handled right, placed in
their bin or let through, per minute of sim time); mean cycle time (sim time between consecutive
boxes handled right).
Exit status 0 when it ran, 2 for bad arguments.
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import sys
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from colorsort.env import parse_cameras
from colorsort.gym_env import ColorSortGymEnv
from colorsort.logs import quiet_robosuite_info
from colorsort.policies import check_policy_spec, checkpoint_cameras, make_policy
from colorsort.variants import VARIANTS, Variant, get_variant


@dataclass
class EvalReport:
    policy: str
    variant: str
    episodes: int = 0
    successes: int = 0
    success_rate: float = 0.0
    success_ci95: tuple[float, float] = (0.0, 0.0)
    correct: int = 0
    misplaced: int = 0
    dropped: int = 0
    distractors: int = 0
    distractors_let_through: int = 0
    boxes_per_minute: float = 0.0
    mean_cycle_time_s: float | None = None
    sim_time_s: float = 0.0
    seeds: list[int] = field(default_factory=list)
    per_episode: list[dict] = field(default_factory=list)


def wilson_interval(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95% Wilson score interval of a success rate (sensible at 0 and 1, unlike the normal approximation)."""
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


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
        context.set_forkserver_preload(["colorsort.evaluate"])  # workers fork from a server that imported it once
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


def aggregate(policy: str, variant: str, results: list[dict]) -> EvalReport:
    """The report over per-episode results (``_Runner.episode``'s dicts, in seed order)."""
    report = EvalReport(policy=policy, variant=variant, seeds=[r["seed"] for r in results])
    cycles: list[float] = []
    handled = 0
    for r in results:
        report.episodes += 1
        report.successes += int(r["success"])
        for key in ("correct", "misplaced", "dropped", "distractors"):
            setattr(report, key, getattr(report, key) + r[key])
        report.distractors_let_through += r["let_through"]
        report.sim_time_s += r["sim_time"]
        handled += len(r["sorted_times"])
        cycles += list(np.diff(r["sorted_times"]))
        report.per_episode.append({k: v for k, v in r.items() if k != "sorted_times"})
    report.success_rate = report.successes / report.episodes
    report.success_ci95 = wilson_interval(report.successes, report.episodes)
    report.boxes_per_minute = 60.0 * handled / report.sim_time_s if report.sim_time_s > 0 else 0.0
    report.mean_cycle_time_s = float(np.mean(cycles)) if cycles else None
    return report


def format_report(r: EvalReport) -> str:
    lo, hi = r.success_ci95
    cycle = f"{r.mean_cycle_time_s:.2f} s" if r.mean_cycle_time_s is not None else "-"
    rows = [
        ("policy", r.policy), ("variant", r.variant), ("episodes", str(r.episodes)),
        ("success rate", f"{100 * r.success_rate:.1f}%  (95% CI {100 * lo:.1f}-{100 * hi:.1f}%)"),
        ("boxes placed correctly", str(r.correct)), ("misplaced", str(r.misplaced)), ("dropped", str(r.dropped)),
        ("distractors let through", f"{r.distractors_let_through}/{r.distractors}"),
        ("boxes per minute", f"{r.boxes_per_minute:.1f}"), ("mean cycle time", cycle),
        ("seeds", f"{r.seeds[0]}..{r.seeds[-1]}" if r.seeds else "-"),
    ]
    return "\n".join(f"{k:<24} {v}" for k, v in rows)


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


def main(argv: list[str] | None = None) -> int:
    quiet_robosuite_info()
    parser = argparse.ArgumentParser(prog="colorsort-eval", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--policy", default="expert", help="expert, random, or a LeRobot checkpoint folder")
    parser.add_argument("--variant", default="default", help="a variant name (see --list)")
    parser.add_argument("--episodes", type=int, default=10, help="episodes to run")
    parser.add_argument("--seed", type=int, default=None, help="first seed (default: the variant's seeds)")
    parser.add_argument("--image-size", type=int, default=None,
                        help="square camera images [px] (default: a checkpoint's own, else 128)")
    parser.add_argument("--cameras", default=None,
                        help="comma-separated cameras or 'none' (default: those a checkpoint was trained on, "
                             "else scene,wrist)")
    parser.add_argument("--episode-length", type=int, default=None,
                        help="steps before an episode is truncated (default: the variant's time limit)")
    parser.add_argument("--envs", type=int, default=1,
                        help="episodes run at once, each in its own process (same numbers whatever N)")
    parser.add_argument("--json", default=None, help="write the metrics as JSON here")
    parser.add_argument("--list", action="store_true", help="print the variants, one per line, and exit")
    args = parser.parse_args(argv)
    if args.list:
        for v in VARIANTS.values():
            print(f"{v.name:<14} {v.gym_id:<34} {v.description}")
        return 0
    if args.episodes < 1:
        parser.error(f"--episodes {args.episodes}: give at least 1")
    if args.envs < 1:
        parser.error(f"--envs {args.envs}: give at least 1")
    try:
        get_variant(args.variant)
        cameras, image_size = observation_settings(args.policy, args.cameras, args.image_size)
        report = evaluate(args.policy, args.variant, args.episodes, args.seed, image_size, cameras,
                          episode_length=args.episode_length, envs=args.envs)
    except ValueError as err:
        print(f"colorsort-eval: error: {err}", file=sys.stderr)
        return 2
    print(format_report(report))
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(asdict(report), indent=1))
        print(f"metrics: {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
