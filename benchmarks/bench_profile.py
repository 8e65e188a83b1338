"""Where an evaluation episode's time goes: physics, controller, observables, rendering, referee, policy.

    python benchmarks/bench_profile.py [--policies expert,baselines/act-state,baselines/act-camera,...]
                                       [--variant default] [--episodes 2]

Runs ``--episodes`` episodes of each policy (``POLICY@VARIANT`` for another variant) in this process under
``cProfile`` and splits their time, cumulative over the functions that own each part, into:

- physics: MuJoCo's ``mj_step1`` and ``mj_step2`` (robosuite's substeps) and ``mj_forward``;
- controller: robosuite's controllers and ColorSort's servo (``envs/servo.py``), less the physics;
- observables: robosuite's observables (cameras excluded) and ColorSort's state vectors;
- rendering: every camera image (the env's own ``render_seconds``): the policy's cameras, the expert's photos;
- referee and cell: the belt, the seal, the spawner and the referee (``Plant.physics_step``, ``control_step``);
- policy: the policy's action, by the clock (``select_action`` for a checkpoint, the expert's ``act``, its photos
  excluded);
- the rest: the remainder of the episode loop (Gymnasium's step, robosuite's step, bookkeeping).

Set-up (building the env, loading the policy) and one warm-up episode are left out. The parts are times under
the profiler, which slows Python more than compiled code: trust the shares, not the seconds.
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import time
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

from colorsort.benchmark.evaluate import EpisodeRunner, EvalConfig, episode_seeds, observation_settings  # noqa: E402
from colorsort.logs import quiet_robosuite_info  # noqa: E402
from colorsort.results import recorded  # noqa: E402
from colorsort.variants import get_variant  # noqa: E402

# each part: (file name fragment, function name) pairs whose cumulative time it holds
PARTS: dict[str, tuple[tuple[str, str], ...]] = {
    "physics": tuple(("~", f"<built-in method mujoco._functions.{f}>") for f in ("mj_step1", "mj_step2", "mj_forward")),
    "controller": (("robots/fixed_base_robot.py", "control"), ("envs/servo.py", "control")),
    "observables": (("robosuite/environments/base.py", "_get_observations"), ("envs/schema.py", "robot_state"),
                    ("envs/schema.py", "box_state"), ("envs/robosuite_task.py", "_sample_observables")),
    "referee and cell": (("cell/plant.py", "physics_step"), ("cell/plant.py", "control_step")),
}


def cumulative(stats: pstats.Stats, keys: tuple[tuple[str, str], ...]) -> float:
    """The summed cumulative time [s] of the functions ``keys`` names (a function under another counted once)."""
    total = 0.0
    for (file, _, name), row in stats.stats.items():  # type: ignore[attr-defined]
        if any(name == n and frag in file for frag, n in keys):
            total += row[3]
    return total


def profile(policy: str, variant: str, episodes: int) -> None:
    cameras, size = observation_settings(policy, None, None)
    runner = EpisodeRunner(EvalConfig(policy, variant, size, cameras))
    seeds = episode_seeds(get_variant(variant), episodes, None)
    runner.episode(seeds[0])  # warm up: numba, the GL context, torch's first call
    acting = runner.policy.act
    spent = {"policy": 0.0}

    def timed_act(obs: Any) -> Any:  # the policy's time by the clock: cProfile loses torch's under inference_mode
        start = time.perf_counter()
        action = acting(obs)
        spent["policy"] += time.perf_counter() - start
        return action

    runner.policy.act = timed_act  # type: ignore[method-assign]
    rendered = runner.env.env.render_seconds
    profiler = cProfile.Profile()
    start = time.perf_counter()
    profiler.enable()
    steps = sum(runner.episode(seed).steps for seed in seeds)
    profiler.disable()
    total = time.perf_counter() - start
    rendering = runner.env.env.render_seconds - rendered
    runner.close()
    stats = pstats.Stats(profiler)
    parts = {name: cumulative(stats, keys) for name, keys in PARTS.items() if name not in ("rendering", "policy")}
    expert = policy == "expert"  # its photos are taken in its act; a checkpoint's cameras render as observables
    parts["observables"] -= 0.0 if expert else rendering
    parts["rendering"] = rendering
    parts["policy"] = spent["policy"] - (rendering if expert else 0.0)
    parts["the rest"] = total - sum(parts.values())
    seen = f"cameras {'+'.join(cameras)} at {size[0]} px" if cameras else "no policy cameras"
    print(f"\n{policy} on '{variant}', {episodes} episodes ({steps} control steps), {seen}: {total:.1f} s under the "
          f"profiler")
    print(f"{'part':<20}{'profiled [s]':>14}{'share':>8}{'per control step [ms]':>24}")
    for name, seconds in parts.items():
        print(f"{name:<20}{seconds:>14.2f}{seconds / total:>8.0%}{1000 * seconds / steps:>24.2f}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--policies", default="expert,baselines/act-state,baselines/act-camera,"
                                         "baselines/act-camera-tracking@tracking")
    p.add_argument("--variant", default="default")
    p.add_argument("--episodes", type=int, default=2, help="profiled episodes a policy, after one to warm up")
    args = p.parse_args()
    quiet_robosuite_info()
    for item in args.policies.split(","):
        policy, _, variant = item.partition("@")
        profile(policy, variant or args.variant, args.episodes)


if __name__ == "__main__":
    with recorded(__file__):
        main()
