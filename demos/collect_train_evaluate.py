"""Collect -> train -> evaluate from Python: the expert's demos as a LeRobot dataset, LeRobot's ACT trained on them,
the policy scored on the benchmark's fixed evaluation seeds.

    python demos/collect_train_evaluate.py --episodes 1 --steps 2 --eval-episodes 1 --episode-length 50

That is a smoke run of a minute or two. A policy that sorts takes about 40 demos and 3,000 or more updates
(``--episodes 40 --steps 3000``: about 40 minutes on 2 CPU cores; docs/baselines.md gives the recipes).
Each stage is the library call a script of your own would make: ``colorsort.data.collect.collect``,
LeRobot's ``lerobot.scripts.lerobot_train.train`` (what ``lerobot-train`` runs, given its config as a
``TrainPipelineConfig`` instead of flags: the same as ``lerobot-train --dataset.repo_id=local/example
--dataset.root=... --policy.type=act ...``), and ``colorsort.benchmark.evaluate.evaluate``. Nothing is downloaded
(``HF_HUB_OFFLINE=1``). The demos are state only, so training loads them in this process (``num_workers=0``): LeRobot
spawns each loader process, which imports torch and LeRobot again before the first batch.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ.setdefault("HF_HUB_OFFLINE", "1")
os.environ.setdefault("MUJOCO_GL", "egl")

from lerobot.configs.default import DatasetConfig  # noqa: E402
from lerobot.configs.train import TrainPipelineConfig  # noqa: E402
from lerobot.policies.act.configuration_act import ACTConfig  # noqa: E402
from lerobot.scripts.lerobot_train import train  # noqa: E402

from colorsort.benchmark.evaluate import evaluate  # noqa: E402
from colorsort.benchmark.metrics import format_report  # noqa: E402
from colorsort.data.collect import collect  # noqa: E402
from colorsort.data.config import CollectConfig  # noqa: E402


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--episodes", type=int, default=40, help="expert demos to record")
    p.add_argument("--steps", type=int, default=3000, help="training updates")
    p.add_argument("--eval-episodes", type=int, default=10, help="evaluation episodes on default")
    p.add_argument("--episode-length", type=int, default=None,
                   help="evaluation steps before truncation (default: the variant's time limit)")
    p.add_argument("--out", type=Path, default=Path("outputs/example"), help="a new folder for everything")
    args = p.parse_args()
    data, run = args.out / "data", args.out / "train"

    summary = collect(CollectConfig(episodes=args.episodes, boxes_per_episode=2, cameras=(), out=str(data),
                                    repo_id="local/example"), progress=False)
    print(f"collected {summary.dataset_episodes} episodes, {summary.dataset_frames} frames: {data}")

    act = ACTConfig(device="cpu", push_to_hub=False, dim_model=128, dim_feedforward=512, n_encoder_layers=2,
                    n_decoder_layers=1, use_vae=False, optimizer_lr=1e-4)
    train(TrainPipelineConfig(dataset=DatasetConfig(repo_id="local/example", root=str(data)), policy=act,
                              steps=args.steps, save_freq=args.steps, batch_size=16, num_workers=0, output_dir=run))
    policy = run / "checkpoints" / "last" / "pretrained_model"
    print(f"trained {args.steps} updates: {policy}")

    report = evaluate(str(policy), "default", args.eval_episodes, cameras=(), progress=False,
                      episode_length=args.episode_length)
    print(format_report(report))


if __name__ == "__main__":
    main()
