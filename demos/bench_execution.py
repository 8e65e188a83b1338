"""How an ACT checkpoint executes its chunks, compared on the same evaluation seeds.

    python demos/bench_execution.py --policy baselines/act-camera-tracking --variant tracking \
        [--executions chunk10,ens0.01] [--episodes 20] [--envs 2]
    python demos/bench_execution.py --policy baselines/act-camera --variant jitter,seed
    python demos/bench_execution.py --policy baselines/act-camera-snapshot --variant jitter --validation

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
import json
import os
import shutil
import tempfile
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

from colorsort.benchmark.evaluate import evaluate, observation_settings  # noqa: E402
from colorsort.logs import quiet_robosuite_info  # noqa: E402
from colorsort.results import recorded  # noqa: E402
from colorsort.variants import VALIDATION_SEEDS, get_variant  # noqa: E402


def inference_settings(execution: str) -> dict[str, float | int | None]:
    """``chunk10`` -> 10 actions open-loop; ``ens0.01`` -> temporal ensembling with coefficient 0.01."""
    if execution.startswith("chunk"):
        return {"n_action_steps": int(execution.removeprefix("chunk")), "temporal_ensemble_coeff": None}
    if execution.startswith("ens"):
        return {"n_action_steps": 1, "temporal_ensemble_coeff": float(execution.removeprefix("ens"))}
    raise ValueError(f"execution {execution!r}: give chunkN (e.g. chunk10) or ensC (e.g. ens0.01)")


def with_execution(policy: Path, execution: str, folder: Path) -> Path:
    """A copy of checkpoint ``policy`` under ``folder`` whose config.json executes as ``execution`` says."""
    copy = folder / execution
    shutil.copytree(policy, copy)
    config = json.loads((copy / "config.json").read_text())
    (copy / "config.json").write_text(json.dumps({**config, **inference_settings(execution)}, indent=4))
    return copy


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
    executions = args.executions.split(",")
    for execution in executions:
        inference_settings(execution)  # ValueError before any episode runs
    variants = args.variant.split(",")
    for variant in variants:
        get_variant(variant)  # ValueError naming the valid variants before any episode runs
    cameras, size = observation_settings(args.policy, None, None)
    seeds = "validation seeds" if args.validation else "evaluation seeds of each"
    print(f"{args.policy} on {', '.join(repr(v) for v in variants)}, first {args.episodes} {seeds}")
    print("| variant | execution | success rate (95% CI) | correct | misplaced | dropped | distractors let through |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        policies = {e: with_execution(Path(args.policy), e, Path(tmp)) for e in executions}
        for variant in variants:
            for execution, policy in policies.items():
                r = evaluate(str(policy), variant, args.episodes, image_size=size, cameras=cameras,
                             progress=False, envs=args.envs, seed=VALIDATION_SEEDS[0] if args.validation else None)
                lo, hi = r.success_ci95
                print(f"| {variant} | {execution} | {100 * r.success_rate:.0f}% ({100 * lo:.0f}-{100 * hi:.0f}%) "
                      f"| {r.correct} | {r.misplaced} | {r.dropped} | {r.distractors_let_through}/{r.distractors} |",
                      flush=True)


if __name__ == "__main__":
    with recorded(__file__):
        main()
