"""ColorSort as Gymnasium vector envs: several cells stepped at once, in this process or in one process each.

    python demos/vector_env.py --envs 2 --steps 40 --mode async

Every benchmark variant is a Gymnasium id (``colorsort/ColorSort-Default-v0``, ``colorsort-eval --list``); its
observation is ``agent_pos`` (the arm's joints, the cup, the ray and the belt), ``environment_state`` (the
simulator's box state) and, with cameras, ``pixels``. ``gym.make_vec`` runs them side by side: ``sync`` in this
process, ``async`` one process per env (each builds its own MuJoCo GL context). Each env resets itself when its
episode ends (Gymnasium's next-step autoreset); the seeds make every env's boxes reproducible.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import colorsort  # noqa: F401  registers the Gymnasium ids


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--envs", type=int, default=2, help="cells stepped at once")
    p.add_argument("--steps", type=int, default=100, help="vector steps of 50 ms")
    p.add_argument("--mode", default="async", choices=["sync", "async"], help="Gymnasium's vectorization mode")
    p.add_argument("--variant", default="colorsort/ColorSort-Default-v0", help="a Gymnasium id of a variant")
    args = p.parse_args()
    envs = gym.make_vec(args.variant, num_envs=args.envs, vectorization_mode=args.mode,
                        vector_kwargs={"context": "spawn"} if args.mode == "async" else None,
                        cameras=("sensor",), image_size=(32, 32))
    obs, _ = envs.reset(seed=list(range(args.envs)))
    print(f"{args.envs} {args.mode} envs: agent_pos {obs['agent_pos'].shape}, environment_state "
          f"{obs['environment_state'].shape}, pixels.sensor {obs['pixels']['sensor'].shape}")
    envs.action_space.seed(0)
    returns = np.zeros(args.envs)
    for _ in range(args.steps):
        obs, reward, terminated, truncated, _ = envs.step(envs.action_space.sample())  # a random policy
        returns += reward
    levels = [round(float(obs["pixels"]["sensor"][k].mean()), 1) for k in range(args.envs)]
    print(f"after {args.steps} steps of random actions: returns {returns.tolist()}, mean sensor pixel {levels}")
    envs.close()


if __name__ == "__main__":
    main()
