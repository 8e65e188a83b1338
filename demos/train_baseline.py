"""The learned baseline: expert demos -> ``lerobot-train`` (a small state-based ACT) -> ``colorsort-eval``.

    python demos/train_baseline.py                       # the README's baseline, about 1.5 h on 2 CPU cores
    python demos/train_baseline.py --ship baselines/act-state-irb140

Every stage is a documented command, run as a subprocess with its command line printed:

1. ``colorsort-collect --cameras none --variant V``: state-only demos of the scripted expert, for
   each training variant and each demo count (``--demos``; episode i of a variant always has the
   same seed, so a smaller set is the first part of a larger one). Several training variants are
   merged into one dataset with LeRobot's ``aggregate_datasets``.
2. ``lerobot-train --policy.type=act`` on ``observation.state`` and ``observation.environment_state``
   (no cameras): the largest set trains ``--steps`` steps, the smaller ones ``--small-steps``.
3. ``colorsort-eval`` on the variants' fixed evaluation seeds: the largest set's policy on every
   ``--eval-variants`` (``--eval-episodes`` on ``default``, ``--other-episodes`` on the others),
   the smaller sets' on ``default``.

It prints a Markdown table (README's learned rows), writes ``OUT/results.json`` and
``OUT/success_vs_demos.png`` (success rate on ``default`` against the number of demos, with 95%
intervals). ``--ship DIR`` copies the largest set's ``pretrained_model`` (config, weights,
processors) to DIR with a README of how it was made and its scores, and the plot beside it.

Stages already finished under OUT (a dataset with its marker, a training run with its last
checkpoint, an evaluation's JSON) are reused, so an interrupted run goes on where it stopped;
``--fresh`` starts over.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shlex
import shutil
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

os.environ.setdefault("HF_HUB_OFFLINE", "1")  # no hub downloads, here or in the commands below
os.environ.setdefault("MUJOCO_GL", "egl")

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent  # the console scripts of this interpreter's environment
REPO_ID = "local/colorsort-baseline"
IRB140_VARIANTS = ("seed", "default", "fast", "jitter", "lighting", "distractors")


@dataclass(frozen=True)
class PolicyPreset:
    """LeRobot ACT settings passed to ``lerobot-train`` as ``--policy.<name>=<value>``."""

    dim_model: int
    dim_feedforward: int
    n_heads: int
    n_encoder_layers: int
    n_decoder_layers: int
    chunk_size: int = 20  # actions predicted per inference [steps of 50 ms]
    n_action_steps: int = 10  # of which the first are executed before the policy looks again
    use_vae: bool = False  # the expert is deterministic: one mode per state, nothing for a latent to explain
    optimizer_lr: float = 1e-4  # LeRobot's 1e-5 is tuned for a pretrained backbone; these start from scratch
    optimizer_lr_backbone: float = 1e-4
    pretrained_backbone_weights: str | None = None  # ImageNet weights would be a download: none at run time

    def args(self) -> list[str]:
        text = {True: "true", False: "false", None: "null"}
        return [f"--policy.{k}={text.get(v, v) if isinstance(v, (bool, type(None))) else v}"
                for k, v in asdict(self).items()]


POLICY_PRESETS = {
    # 0.67 M parameters, about 3 updates per second at batch 64 on 2 CPU cores
    "state": PolicyPreset(dim_model=128, dim_feedforward=512, n_heads=4, n_encoder_layers=2, n_decoder_layers=1),
    # LeRobot's ACT size with a ResNet-18 trained from scratch on the cameras: for a GPU
    "vision": PolicyPreset(dim_model=512, dim_feedforward=3200, n_heads=8, n_encoder_layers=4, n_decoder_layers=1),
}


@dataclass(frozen=True)
class BaselineConfig:
    demos: tuple[int, ...] = (8, 40, 200)  # demo counts, the last one trains the shipped policy
    # demos split evenly over these: a default-only policy sorted 10/10 default episodes but let no
    # distractor through (0/10), misplaced jittered boxes (6/10) and stalled on fast (6/10)
    train_variants: tuple[str, ...] = ("default", "jitter", "fast", "distractors")
    boxes_per_episode: int = 3
    steps: int = 6000  # updates for the largest set
    small_steps: int = 2500  # updates for the smaller sets
    batch_size: int = 64
    eval_variants: tuple[str, ...] = IRB140_VARIANTS
    eval_episodes: int = 50  # on default
    other_episodes: int = 20  # on every other variant
    episode_length: int | None = None  # evaluation steps before truncation (None: the variant's time limit)
    envs: int = 2  # evaluation processes
    workers: int = 2  # collection processes
    out: str = "outputs/baseline"
    cameras: tuple[str, ...] = ()  # () trains on states; cameras train a vision policy (see README's GPU recipe)
    image_size: int = 128  # [px], square, with cameras
    device: str = "cpu"  # lerobot-train's --policy.device: "cpu", "cuda" or "mps"

    @property
    def policy(self) -> PolicyPreset:
        return POLICY_PRESETS["vision" if self.cameras else "state"]

    @property
    def label(self) -> str:
        return f"ACT, {'+'.join(self.cameras) if self.cameras else 'state'}"

    def __post_init__(self) -> None:
        from colorsort.variants import get_variant

        for name in self.train_variants + self.eval_variants:
            get_variant(name)  # ValueError naming the valid variants
        if not self.demos or any(n < len(self.train_variants) for n in self.demos) or list(self.demos) != sorted(set(self.demos)):
            raise ValueError(f"demos={self.demos}: give increasing counts, each at least the number of training "
                             f"variants ({len(self.train_variants)})")
        from colorsort.cell.cameras import CAMERAS

        if any(c not in CAMERAS for c in self.cameras):
            raise ValueError(f"cameras={self.cameras}: give names from {list(CAMERAS)}, or none")
        if self.device not in ("cpu", "cuda", "mps"):
            raise ValueError(f"device={self.device!r}: valid devices are ['cpu', 'cuda', 'mps']")
        if "default" not in self.eval_variants:
            raise ValueError("eval_variants must include 'default' (the plot's variant)")
        for name in ("steps", "small_steps", "batch_size", "eval_episodes", "other_episodes", "envs", "workers"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name}={getattr(self, name)}: give at least 1")


def run(cmd: list[str], log: Path | None = None) -> float:
    """Run ``cmd`` (printed first), its output to ``log`` if given; returns its wall time [s]."""
    print("$ " + shlex.join(cmd), flush=True)
    t = time.perf_counter()
    if log is None:
        result = subprocess.run(cmd, cwd=REPO)
    else:
        log.parent.mkdir(parents=True, exist_ok=True)
        with log.open("w") as f:
            result = subprocess.run(cmd, cwd=REPO, stdout=f, stderr=subprocess.STDOUT)
    if result.returncode != 0:
        tail = log.read_text()[-3000:] if log else ""
        raise RuntimeError(f"exit code {result.returncode}: {shlex.join(cmd)}\n{tail}")
    return time.perf_counter() - t


def split_demos(n: int, variants: tuple[str, ...]) -> dict[str, int]:
    """``n`` demos over the variants, counts differing by at most one."""
    return {v: n // len(variants) + (k < n % len(variants)) for k, v in enumerate(variants)}


def collect(config: BaselineConfig, n: int, out: Path) -> Path:
    """The state-only dataset of ``n`` demos (reused if there)."""
    root = out / "data" / f"demos-{n}"
    if (root / "meta" / "info.json").is_file() and (root / "meta" / "complete").is_file():
        print(f"reusing {root}")
        return root
    parts = []
    for k, (variant, count) in enumerate(split_demos(n, config.train_variants).items()):
        part = out / "data" / f"{variant}-{count}"
        if not (part / "meta" / "colorsort.json").is_file():
            shutil.rmtree(part, ignore_errors=True)
            run([str(BIN / "colorsort-collect"), "--variant", variant, "--episodes", str(count),
                 "--boxes-per-episode", str(config.boxes_per_episode), "--seed", str(1_000_000 * k),
                 "--cameras", ",".join(config.cameras) or "none", "--image-size", str(config.image_size),
                 "--workers", str(config.workers), "--out", str(part), "--repo-id", REPO_ID],
                log=out / "logs" / f"collect-{variant}-{count}.log")
        parts.append(part)
    shutil.rmtree(root, ignore_errors=True)
    merged = out / "data" / f".demos-{n}.merged"
    shutil.rmtree(merged, ignore_errors=True)
    from lerobot.datasets.aggregate import aggregate_datasets

    aggregate_datasets([REPO_ID] * len(parts), REPO_ID, roots=parts, aggr_root=merged if config.cameras else root)
    if config.cameras:  # a vision policy must see the box's colour and pose, not read them from the simulator
        from lerobot.datasets.dataset_tools import remove_feature
        from lerobot.datasets.lerobot_dataset import LeRobotDataset

        remove_feature(LeRobotDataset(REPO_ID, root=merged), "observation.environment_state", output_dir=root,
                       repo_id=REPO_ID)
        shutil.rmtree(merged)
    (root / "meta" / "complete").write_text("")
    return root


def train(config: BaselineConfig, data: Path, steps: int, out: Path) -> tuple[Path, float]:
    """``lerobot-train`` on ``data``; returns the last checkpoint and the training wall time [s] (reused if there)."""
    run_dir = out / "train" / f"{data.name}-{steps}steps"
    model = run_dir / "checkpoints" / "last" / "pretrained_model"
    timing = run_dir / "wall_seconds.txt"
    if (model / "config.json").is_file() and timing.is_file():
        print(f"reusing {model}")
        return model, float(timing.read_text())
    if run_dir.exists():
        print(f"removing {run_dir}, an unfinished training run")
        shutil.rmtree(run_dir)
    seconds = run([str(BIN / "lerobot-train"), f"--dataset.repo_id={REPO_ID}", f"--dataset.root={data}",
                   "--policy.type=act", f"--policy.device={config.device}", "--policy.push_to_hub=false",
                   *config.policy.args(),
                   f"--batch_size={config.batch_size}", f"--steps={steps}", f"--save_freq={steps}",
                   "--log_freq=200", "--num_workers=1", "--seed=1000", "--wandb.enable=false",
                   f"--output_dir={run_dir}"],
                  log=out / "logs" / f"train-{run_dir.name}.log")
    timing.write_text(f"{seconds:.1f}")
    return model, seconds


def evaluate(config: BaselineConfig, model: Path, variant: str, out: Path, tag: str) -> dict:
    """``colorsort-eval`` of ``model`` on ``variant``'s evaluation seeds; its JSON report (reused if there)."""
    path = out / "eval" / f"{tag}-{variant}.json"
    if path.is_file():
        print(f"reusing {path}")
        return json.loads(path.read_text())
    episodes = config.eval_episodes if variant == "default" else config.other_episodes
    cmd = [str(BIN / "colorsort-eval"), "--policy", str(model), "--variant", variant, "--episodes", str(episodes),
           "--envs", str(config.envs), "--json", str(path)]
    if config.episode_length:
        cmd += ["--episode-length", str(config.episode_length)]
    run(cmd, log=out / "logs" / f"eval-{tag}-{variant}.log")
    return json.loads(path.read_text())


def plot(rows: list[dict], label: str, path: Path) -> None:
    """Success rate on ``default`` (95% Wilson interval) against the number of demos."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = [r["demos"] for r in rows]
    rate = [100 * r["success_rate"] for r in rows]
    lo = [100 * (r["success_rate"] - r["success_ci95"][0]) for r in rows]
    hi = [100 * (r["success_ci95"][1] - r["success_rate"]) for r in rows]
    fig, ax = plt.subplots(figsize=(5, 3.5), dpi=120)
    ax.errorbar(n, rate, yerr=[lo, hi], marker="o", capsize=4)
    for r, x, y in zip(rows, n, rate):
        ax.annotate(f"{r['steps']} steps", (x, y), textcoords="offset points", xytext=(6, -12), fontsize=7)
    ax.set_xscale("log")
    ax.set_xticks(n, [str(x) for x in n])
    ax.set_ylim(-2, 102)
    ax.set_xlabel("expert demos (episodes of 3 boxes)")
    ax.set_ylabel("success on default [%]")
    ax.set_title(f"{label} on ColorSort, {rows[0]['episodes']} evaluation seeds", fontsize=9)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)


def table(results: list[dict], label: str) -> str:
    lines = ["| variant | policy | demos | training | success rate (95% CI) | correct | misplaced | dropped "
             "| distractors let through | boxes/min | mean cycle [s] |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in results:
        lo, hi = r["success_ci95"]
        cycle = f"{r['mean_cycle_time_s']:.2f}" if r["mean_cycle_time_s"] is not None else "-"
        lines.append(f"| {r['variant']} | {label} | {r['demos']} | {r['steps']} steps, {r['train_minutes']:.0f} min "
                     f"| {100 * r['success_rate']:.0f}% ({100 * lo:.0f}-{100 * hi:.0f}%) | {r['correct']} | {r['misplaced']} "
                     f"| {r['dropped']} | {r['distractors_let_through']}/{r['distractors']} | {r['boxes_per_minute']:.1f} "
                     f"| {cycle} |")
    return "\n".join(lines)


def commit() -> str:
    try:
        sha = subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO, capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=REPO, capture_output=True,
                               text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown (not a git checkout)"
    return sha + (" (with uncommitted changes)" if dirty else "")


def parameters(model: Path) -> int:
    """Parameters stored in a pretrained_model folder's weights."""
    from safetensors import safe_open

    with safe_open(str(model / "model.safetensors"), "np") as f:
        return sum(math.prod(f.get_slice(k).get_shape()) for k in f.keys())


def machine(device: str) -> str:
    """One line: this machine's CPU cores and the training device."""
    return f"a {os.cpu_count()}-core machine, training on {'the CPU' if device == 'cpu' else device}"


def ship(config: BaselineConfig, model: Path, results: list[dict], plot_path: Path, dest: Path, argv: list[str],
         started: str, wall_s: float) -> None:
    """The largest set's policy to ``dest``: LeRobot's pretrained_model files, the plot and a README."""
    dest.mkdir(parents=True, exist_ok=True)
    for f in model.iterdir():
        shutil.copy2(f, dest / f.name)
    shutil.copy2(plot_path, dest / plot_path.name)
    largest = [r for r in results if r["demos"] == config.demos[-1]]
    size_mb = sum(f.stat().st_size for f in dest.iterdir()) / 1e6
    mix = ", ".join(f"{c} on {v}" for v, c in split_demos(config.demos[-1], config.train_variants).items())
    inputs = (f"`observation.state` and the cameras {', '.join(config.cameras)} at {config.image_size} px (not "
              "`observation.environment_state`: the policy sees the boxes)" if config.cameras else
              "`observation.state` and `observation.environment_state`: no cameras")
    (dest / "README.md").write_text(f"""# {dest.name}: a learned baseline for ColorSort (IRB 140), {config.label}

LeRobot ACT ({parameters(dest) / 1e6:.2f} M parameters, {config.policy.dim_model}-dim, {config.policy.n_encoder_layers} encoder and
{config.policy.n_decoder_layers} decoder layers, chunks of {config.policy.chunk_size} actions of which
{config.policy.n_action_steps} are executed, no VAE, learning rate {config.policy.optimizer_lr}) on
{inputs}. {size_mb:.1f} MB.

Made by `python demos/train_baseline.py {shlex.join(argv)}` on commit {commit()}, started {started},
{wall_s / 60:.0f} min for this run (stages reused from earlier runs not counted) on {machine(config.device)}: {config.demos[-1]} expert demos tried
({mix}; {config.boxes_per_episode} boxes each), {largest[0]['steps']} updates at batch
{config.batch_size} ({largest[0]['train_minutes']:.0f} min of `lerobot-train`).

Run it:

```
colorsort-eval --policy {dest} --variant default --episodes 50
HF_HUB_OFFLINE=1 lerobot-eval --env.type=colorsort --env.task=ColorSort-Default-v0 --env.cameras={",".join(config.cameras) or "none"} --env.image_size={config.image_size} \\
    --policy.path={dest} --policy.device=cpu --eval.n_episodes=50 --eval.batch_size=2
```

Scores (`colorsort-eval`, each variant's fixed evaluation seeds):

{table(largest, config.label)}

Success on `default` against the number of demos: `success_vs_demos.png`.
""")
    print(f"shipped {dest} ({size_mb:.1f} MB)")


def parse_args(argv: list[str]) -> tuple[BaselineConfig, argparse.Namespace]:
    d = BaselineConfig()
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--demos", default=",".join(map(str, d.demos)), help="increasing demo counts, comma-separated")
    p.add_argument("--train-variants", default=",".join(d.train_variants), help="variants the demos come from")
    p.add_argument("--boxes-per-episode", type=int, default=d.boxes_per_episode)
    p.add_argument("--steps", type=int, default=d.steps, help="training updates for the largest set")
    p.add_argument("--small-steps", type=int, default=d.small_steps, help="training updates for the smaller sets")
    p.add_argument("--batch-size", type=int, default=d.batch_size)
    p.add_argument("--eval-variants", default=",".join(d.eval_variants), help="variants the largest set's policy is evaluated on")
    p.add_argument("--eval-episodes", type=int, default=d.eval_episodes, help="evaluation episodes on default")
    p.add_argument("--other-episodes", type=int, default=d.other_episodes, help="evaluation episodes on the other variants")
    p.add_argument("--episode-length", type=int, default=None, help="evaluation steps before truncation")
    p.add_argument("--envs", type=int, default=d.envs, help="evaluation processes")
    p.add_argument("--workers", type=int, default=d.workers, help="collection processes")
    p.add_argument("--out", default=d.out, help="working folder: datasets, training runs, evaluations, logs")
    p.add_argument("--cameras", default="none", help="'none' (a state-based policy) or cameras for a vision policy")
    p.add_argument("--image-size", type=int, default=d.image_size, help="camera images [px], square")
    p.add_argument("--device", default=d.device, help="lerobot-train's device: cpu, cuda or mps")
    p.add_argument("--ship", default=None, help="copy the largest set's policy here with a README")
    p.add_argument("--fresh", action="store_true", help="delete OUT first instead of reusing its finished stages")
    args = p.parse_args(argv)
    try:
        config = BaselineConfig(
            demos=tuple(int(x) for x in args.demos.split(",")), train_variants=tuple(args.train_variants.split(",")),
            boxes_per_episode=args.boxes_per_episode, steps=args.steps, small_steps=args.small_steps,
            batch_size=args.batch_size, eval_variants=tuple(args.eval_variants.split(",")),
            eval_episodes=args.eval_episodes, other_episodes=args.other_episodes, episode_length=args.episode_length,
            envs=args.envs, workers=args.workers, out=args.out,
            cameras=() if args.cameras == "none" else tuple(args.cameras.split(",")), image_size=args.image_size,
            device=args.device)
    except ValueError as err:
        p.error(str(err))
        raise
    return config, args


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    config, args = parse_args(argv)
    if args.ship and Path(args.ship).exists() and any(Path(args.ship).iterdir()):
        print(f"train_baseline.py: error: {args.ship} exists: remove it first, or ship elsewhere", file=sys.stderr)
        return 2
    out = Path(config.out)
    if args.fresh:
        shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True, exist_ok=True)
    started, t0 = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), time.perf_counter()
    results: list[dict] = []
    for n in config.demos:
        largest = n == config.demos[-1]
        steps = config.steps if largest else config.small_steps
        data = collect(config, n, out)
        model, seconds = train(config, data, steps, out)
        episodes = json.loads((data / "meta" / "info.json").read_text())["total_episodes"]
        for variant in (config.eval_variants if largest else ("default",)):
            report = evaluate(config, model, variant, out, model.parents[2].name)
            row = {"demos": episodes, "steps": steps,
                   "train_minutes": seconds / 60, **{k: v for k, v in report.items() if k != "per_episode"}}
            results.append(row)
            print(table([row], config.label).splitlines()[-1], flush=True)
    on_default = [r for r in results if r["variant"] == "default"]
    plot_path = out / "success_vs_demos.png"
    plot(on_default, config.label, plot_path)
    wall = time.perf_counter() - t0
    (out / "results.json").write_text(json.dumps({"config": asdict(config), "wall_s": wall, "results": results}, indent=1))
    print(f"\n{table(results, config.label)}\n\nplot: {plot_path}\nresults: {out / 'results.json'}\n"
          f"wall time: {wall / 60:.1f} min (stages reused from earlier runs excluded)")
    if args.ship:
        ship(config, model, results, plot_path, Path(args.ship), argv, started, wall)
    return 0


if __name__ == "__main__":
    sys.exit(main())
