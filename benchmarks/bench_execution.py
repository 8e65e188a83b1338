"""How an ACT checkpoint executes its chunks, compared on the same evaluation seeds.

    python benchmarks/bench_execution.py --policy baselines/act-camera-tracking --variant tracking \
        [--executions chunk10,ens0.01] [--episodes 20] [--envs 2]
    python benchmarks/bench_execution.py --policy baselines/act-camera --variant jitter,seed
    python benchmarks/bench_execution.py --policy baselines/act-camera-snapshot --variant jitter --validation

ACT predicts a chunk of actions per inference. ``chunkN`` executes the first N of each chunk
open-loop (LeRobot's default is 10 of 20); ``ensC`` predicts every step and executes the average of
every chunk's prediction for that step, weights exp(-C * age) (ACT's temporal ensembling). Neither
setting changes the trained weights, so each execution is the same checkpoint with its
``config.json`` rewritten in a temporary copy, scored by ``colorsort.benchmark.evaluate`` on the
variant's first ``--episodes`` evaluation seeds, or with ``--validation`` on the validation seeds
(``colorsort.variants.VALIDATION_SEEDS``, which no evaluation scores: an execution chosen there is
not chosen on the seeds it is then scored on). ``--variant`` takes several, comma-separated. Prints
one row per variant and execution: success with its 95% Wilson interval and the box outcomes.
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

from studies.chunk_execution import execution_table  # noqa: E402

from colorsort.logs import quiet_robosuite_info  # noqa: E402
from colorsort.results import recorded  # noqa: E402


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--policy", required=True, help="a LeRobot ACT checkpoint folder")
    p.add_argument("--variant", default="tracking", help="a variant, or several comma-separated")
    p.add_argument("--executions", default="chunk10,ens0.01", help="comma-separated chunkN or ensC")
    p.add_argument("--episodes", type=int, default=20)
    p.add_argument("--envs", type=int, default=2)
    p.add_argument("--validation", action="store_true",
                   help="play the validation seeds (20000 on) instead of the evaluation seeds")
    args = p.parse_args()
    quiet_robosuite_info()
    for line in execution_table(args.policy, args.variant.split(","), args.executions.split(","), args.episodes,
                                args.envs, args.validation):
        print(line, flush=True)


if __name__ == "__main__":
    with recorded(__file__):
        main()
