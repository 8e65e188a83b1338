"""What an ACT checkpoint predicts for the belt-pass command where the expert let a box through.

    python demos/probe_pass.py --policy CHECKPOINT --dataset DATASET_ROOT

A state policy (``observation.state`` and ``observation.environment_state``) is fed the dataset's
own frames, one at a time, where the expert let a yellow or purple box through: the box at the
ray with the belt stopped (the decision, whose chunk of labels is belt-pass on), and the frames
while the belt runs it past the ray. Prints, per kind of frame, how many there are, the mean
label and the mean predicted belt-pass of the first action of each chunk (+1 on, -1 off), and how
many predictions are on. A policy that predicts off at the decision holds the box at the sensor
until the time limit (``distractors`` 0%). It prints only (no docs/results file): the checkpoints it
probes come from ``colorsort-baseline`` runs, not from ``make bench``.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

os.environ.setdefault("HF_HUB_OFFLINE", "1")

from colorsort.data.schema import ACTION, ENV_STATE, STATE  # noqa: E402


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--policy", required=True, help="a state policy's pretrained_model folder")
    p.add_argument("--dataset", required=True, help="a LeRobot dataset root recorded by colorsort-collect")
    args = p.parse_args()

    import pandas as pd
    import torch

    from colorsort.benchmark.policies import LeRobotPolicy

    policy = LeRobotPolicy(args.policy)
    frames = pd.concat(pd.read_parquet(f) for f in sorted(Path(args.dataset).glob("data/**/*.parquet")))
    state, env_state = np.stack(frames[STATE].to_numpy()), np.stack(frames[ENV_STATE].to_numpy())
    action = np.stack(frames[ACTION].to_numpy())
    belt_pass, belt_running = action[:, -1] > 0.0, state[:, -1] > 0.5
    kinds = {"decision: box at the ray, belt stopped": belt_pass & ~belt_running,
             "passing: belt running the box past the ray": belt_pass & belt_running}

    def first_action(i: int) -> float:
        batch = {STATE: torch.tensor(state[i][None], dtype=torch.float32),
                 ENV_STATE: torch.tensor(env_state[i][None], dtype=torch.float32), "task": [""]}
        with torch.no_grad():
            chunk = policy.postprocessor(policy.policy.predict_action_chunk(policy.preprocessor(batch)))
        return float(chunk[0, 0, -1])

    print(f"{args.policy} on {args.dataset} ({len(frames)} frames)")
    print("| frames | count | label (mean) | predicted belt-pass (mean) | predicted on |")
    print("| --- | --- | --- | --- | --- |")
    for kind, mask in kinds.items():
        rows = np.flatnonzero(mask)
        predicted = np.array([first_action(i) for i in rows])
        print(f"| {kind} | {len(rows)} | {action[rows, -1].mean():+.2f} | {predicted.mean():+.2f} | "
              f"{int((predicted > 0).sum())} of {len(rows)} |")


if __name__ == "__main__":
    main()
