"""Does a camera policy decide by the box's colour or by its own stillness? Its pass-or-pick at the frames of the
demos where a box waits at the ray and the arm stands still.

    python benchmarks/probe_stillness.py --policy baselines/act-camera-snapshot-dr \\
        --data outputs/baselines/camera-snapshot-touch-dr/data/distractors-32-24e1def7

Every ``--every``-th frame of the recorded datasets (``--data``, one or more; each must keep its
``observation.environment_state``, as the recorded parts do) where the ray sees a box, the cup is off and no joint
moves faster than 0.05 rad/s is given to the policy, alone (its queue reset); printed per colour of the waiting
box (from the recorded box state): how many frames, on how many of them the expert passed the box (its stored
``belt_pass`` above 0) and on how many the policy would. A policy that passes a class colour there that the
expert picks has learned that a still arm means "let it through" (the demos' ``late_pass`` holds label a still
arm *pass* for up to ``late_pass`` frames a distractor, ``late_pick`` *go* for up to ``late_pick`` frames a
pick). ``--moving`` adds the same frames with the joint velocities set to 0.3 rad/s. Without ``--policy`` it
counts the demos' frames and the expert's passes alone.
"""

from __future__ import annotations

import argparse
import os
from collections import Counter
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from colorsort.benchmark.policies import LeRobotPolicy

os.environ.setdefault("HF_HUB_OFFLINE", "1")

STILL = 0.05  # rad/s: a joint slower than this stands still
MOVING = 0.3  # rad/s: the joint velocity --moving puts in the state


def probe(policy_path: str | None, data: list[str], every: int, moving: bool) -> dict[str, Counter]:
    """Per colour: ``frames``, ``expert`` (passes), with a policy ``policy`` (passes) and, with ``moving``,
    ``policy_moving``."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from colorsort.benchmark.policies import LeRobotPolicy
    from colorsort.cell.observation import FLAGS, StateLayout
    from colorsort.config import COLORS

    policy = LeRobotPolicy(policy_path) if policy_path else None
    if policy:
        policy.task = ""
    table: dict[str, Counter] = {}
    for root in data:
        ds = LeRobotDataset("local/colorsort-probe", root=root, video_backend="pyav")
        cols = ds.hf_dataset.with_format("numpy")
        state, action = np.stack(cols["observation.state"]), np.stack(cols["action"])
        box = np.stack(cols["observation.environment_state"])
        (camera,) = ds.meta.camera_keys
        layout = StateLayout(n_joints=(state.shape[1] - 7 - len(FLAGS)) // 2)
        for i in range(0, len(state), every):
            s = state[i]
            vel = s[layout.joint_vel: layout.joint_vel + layout.n_joints]
            ray, suction = s[layout.flags + FLAGS.index("ray.blocked")], s[layout.flags + FLAGS.index("suction.on")]
            if ray < 0.5 or suction > 0.5 or np.abs(vel).max() > STILL or box[i, :len(COLORS)].max() < 0.5:
                continue
            colour = list(COLORS)[int(box[i, :len(COLORS)].argmax())]
            row = table.setdefault(colour, Counter())
            row["frames"] += 1
            row["expert"] += int(action[i, -1] > 0)
            if policy is None:
                continue
            image = (ds[i][camera].numpy().transpose(1, 2, 0) * 255).round().astype(np.uint8)
            row["policy"] += int(decide(policy, image, s, camera) > 0)
            if moving:
                fast = s.copy()
                fast[layout.joint_vel: layout.joint_vel + layout.n_joints] = MOVING
                row["policy_moving"] += int(decide(policy, image, fast, camera) > 0)
    return table


def decide(policy: LeRobotPolicy, image: np.ndarray, state: np.ndarray, camera: str) -> float:
    """The policy's ``belt_pass`` for one frame, its queue reset first."""
    policy.policy.reset()
    name = camera.removeprefix("observation.images.")
    action = policy.act({"pixels": {name: image}, "agent_pos": state.astype(np.float32)})
    return float(action[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--policy", help="a LeRobot checkpoint folder (none: the demos' counts alone)")
    parser.add_argument("--data", nargs="+", required=True, help="recorded datasets (the parts, with the box state)")
    parser.add_argument("--every", type=int, default=3, help="every N-th frame (default 3)")
    parser.add_argument("--moving", action="store_true", help="also the same frames with the joints moving")
    args = parser.parse_args()
    table = probe(args.policy, args.data, args.every, args.moving)
    print(f"{args.policy or 'the demos'}: frames with a box waiting at a still arm, passes by the expert"
          + (" and by the policy" if args.policy else ""))
    for colour, row in sorted(table.items()):
        extra = f", policy {row['policy']:>5}" if args.policy else ""
        extra += f", the policy with the arm moving {row['policy_moving']}" if args.policy and args.moving else ""
        print(f"  {colour:<7} {row['frames']:>5} frames: expert {row['expert']:>5}{extra}")


if __name__ == "__main__":
    main()
