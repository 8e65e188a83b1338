"""Shipped policies on the batched cell against their published CPU-cell scores, variant by variant.

    python benchmarks/bench_warp_scores.py --policies baselines/act-state,baselines/act-camera-snapshot \
        --episodes 200 --device cuda:0

For each policy and each variant its ``scores.json`` scored (the CPU cell, the variant's evaluation seeds), the
batched cell runs ``--episodes`` episodes from the first evaluation seed (seeds 10000 on: the CPU cell's
seeds first, then more), ``--envs`` worlds at once. The table gives both backends' success rates with their 95%
intervals and whether the batched rate lies inside the CPU cell's interval; then, on the seeds both ran, how many
episodes ended the same way and how many sorted the same boxes into the same bins. The CPU rows are the shipped
checkpoint's: a baseline's ``scores.json`` lists its shipped training seed first.

A GPU machine without robosuite runs the evaluations with ``--specs DIR`` (a ``CellSpec`` per variant saved as
``DIR/<variant>``, ``CellSpec.save``) and ``--json FILE`` each; ``--merge FILE...`` then writes the table from
those files on any machine.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from colorsort.results import recorded


def shipped_rows(policy: str) -> dict[str, dict]:
    """The CPU cell's score of the shipped checkpoint on each variant (``scores.json``: its seed's rows first)."""
    rows = json.loads((Path(policy) / "scores.json").read_text())["rows"]
    return {r["variant"]: r for r in rows if r["seed"] == rows[0]["seed"]}


def evaluate(policy: str, variant: str, episodes: int, envs: int, device: str, specs: str | None) -> dict:
    """One batched evaluation, with what the comparison needs."""
    from colorsort.batched.evaluate import evaluate_batched
    from colorsort.batched.spec import CellSpec
    from colorsort.variants import get_variant

    spec = CellSpec.load(Path(specs) / variant) if specs else None
    first_seed = get_variant(variant).seeds[0]
    run = evaluate_batched(policy, variant, episodes, seed=first_seed, envs=envs, device=device, progress=False,
                           spec=spec)
    r = run.report
    return {"policy": policy, "variant": variant, "device": device, "envs": envs, "episodes": r.episodes,
            "successes": r.successes, "success_ci95": list(r.success_ci95), "correct": r.correct,
            "misplaced": r.misplaced, "dropped": r.dropped, "seconds": run.timing.seconds,
            "control_steps": run.timing.control_steps, "per_episode": r.per_episode}


def boxes(episode: dict) -> list[tuple]:
    return [(b["color"], b["outcome"], b["bin"]) for b in episode["boxes"]]


def table(runs: list[dict], gpu: str) -> str:
    """The comparison as markdown."""
    lines = [f"The batched cell on {gpu} against the CPU cell's published scores (the shipped checkpoint's rows "
             "of `scores.json`).", "",
             "| policy | variant | CPU cell (95% CI), episodes | batched cell (95% CI), episodes | inside the CPU "
             "interval | same end, same boxes (on the CPU's seeds) | correct / misplaced / dropped (batched) "
             "| wall [s] |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    inside_all = 0
    for run in runs:
        cpu = shipped_rows(run["policy"])[run["variant"]]
        rate = run["successes"] / run["episodes"]
        lo, hi = cpu["success_ci95"]
        inside = lo - 1e-9 <= rate <= hi + 1e-9
        inside_all += inside
        by_seed = {e["seed"]: e for e in run["per_episode"]}
        pairs = [(e, by_seed[e["seed"]]) for e in cpu["per_episode"] if e["seed"] in by_seed]
        same_end = sum(a["ended"] == b["ended"] for a, b in pairs)
        same_boxes = sum(boxes(a) == boxes(b) for a, b in pairs)
        glo, ghi = run["success_ci95"]
        lines.append(
            f"| `{Path(run['policy']).name}` | `{run['variant']}` | {100 * cpu['success_rate']:.0f}% "
            f"({100 * lo:.0f}-{100 * hi:.0f}%), {cpu['episodes']} | {100 * rate:.1f}% ({100 * glo:.1f}-"
            f"{100 * ghi:.1f}%), {run['episodes']} | {'yes' if inside else '**no**'} | {same_end} / {same_boxes} "
            f"of {len(pairs)} | {run['correct']} / {run['misplaced']} / {run['dropped']} | {run['seconds']:.0f} |")
    lines += ["", f"Inside the CPU cell's interval: {inside_all} of {len(runs)} (policy, variant) pairs."]
    return "\n".join(lines) + "\n"


def main() -> int:
    with recorded(__file__):
        return run()


def run() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--policies", default="baselines/act-state,baselines/act-camera-snapshot")
    parser.add_argument("--variants", default=None, help="default: every variant a policy's scores.json holds")
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--envs", type=int, default=None, help="worlds at once (default: --episodes)")
    parser.add_argument("--device", default="cuda:0", help="Warp's device")
    parser.add_argument("--specs", default=None, help="saved CellSpecs, one folder per variant")
    parser.add_argument("--json", default=None, help="write the runs here")
    parser.add_argument("--merge", nargs="+", default=None, help="tabulate these --json files; evaluate nothing")
    args = parser.parse_args()

    if args.merge:
        runs = [r for f in args.merge for r in json.loads(Path(f).read_text())["runs"]]
        gpu = json.loads(Path(args.merge[0]).read_text())["gpu"]
    else:
        import torch

        gpu = torch.cuda.get_device_name(0) if args.device.startswith("cuda") else "Warp's CPU device"
        runs = []
        for policy in args.policies.split(","):
            variants = args.variants.split(",") if args.variants else list(shipped_rows(policy))
            for variant in variants:
                runs.append(evaluate(policy, variant, args.episodes, args.envs or args.episodes, args.device,
                                     args.specs))
                print(f"{policy} on {variant}: {runs[-1]['successes']}/{runs[-1]['episodes']} in "
                      f"{runs[-1]['seconds']:.0f} s", flush=True)
                if args.json:
                    Path(args.json).write_text(json.dumps({"gpu": gpu, "runs": runs}, default=str))
    print(table(runs, gpu))
    return 0


if __name__ == "__main__":
    sys.exit(main())
