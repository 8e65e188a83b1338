"""ColorSort as a robosuite environment: ``suite.make``, the scripted expert driving it, and what the cell reports.

    python demos/robosuite_env.py --boxes 2 --seed 0

The task is a robosuite ``ManipulationEnv``: observations are robosuite's dict (the arm's joints and the
cup's pose, the ray, the belt, each camera's image), the action is 6 joint targets [rad], the suction
command and the belt-pass command (each -1 off, +1 on). The expert reads the same observations a policy
would; every box that leaves the belt is an event (placed in the bin of its colour, misplaced, dropped).
"""

from __future__ import annotations

import argparse

import colorsort  # noqa: F401  registers the task, the IRB 140 and the gripper; first: it quiets robosuite's notices
from colorsort.cell.referee import Outcome, describe_box
from colorsort.expert.factory import make_expert


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--boxes", type=int, default=3, help="boxes that must leave the belt")
    p.add_argument("--seed", type=int, default=0, help="the env's seed")
    args = p.parse_args()
    import robosuite as suite

    env = suite.make("ColorSort", robots="IRB140", preset="default", seed=args.seed, has_renderer=False,
                     has_offscreen_renderer=True, use_camera_obs=False, ignore_done=True)
    obs = env.reset()
    print(f"action: {env.action_dim} numbers (6 joint targets [rad], suction, belt pass); "
          f"observations: {', '.join(sorted(k for k in obs if not k.endswith('image')))}")
    expert = make_expert(env)
    expert.reset(obs)
    while len(env.events) < args.boxes and env.cur_time < 60.0 * args.boxes:
        obs, reward, done, info = env.step(expert.act(obs))
    for event in env.events:
        print(f"{event.time:6.1f} s  {describe_box(event.color, event.outcome, event.bin)}")
    placed = sum(e.outcome is Outcome.PLACED for e in env.events)
    print(f"{placed} of {len(env.events)} boxes placed in the bin of their colour in {env.cur_time:.1f} s of sim time")
    env.close()


if __name__ == "__main__":
    main()
