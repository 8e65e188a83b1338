"""Record the scripted expert's episodes as a LeRobot v3.0 dataset.

Example::

    colorsort-collect --episodes 100 --boxes-per-episode 1 --preset default --robot IRB140 \\
        --seed 0 --out datasets/colorsort --repo-id local/colorsort --cameras scene,wrist \\
        --image-size 128 --fps 20 --workers 2 --vcodec libsvtav1

Episode ``i`` (0 <= i < episodes) runs with env seed ``seed + i``, so a dataset is the same
whatever the number of workers; only episodes in which every box ended where it belongs are
kept (the summary says how many were tried and why the others were not). ``--workers N``
records N shards side by side and merges them with lerobot's ``aggregate_datasets``.

The output directory only ever holds a complete dataset: shards are recorded in a hidden
staging folder beside it (``.<name>.staging``) and the merged result replaces the output in one
rename. Ctrl-C stops recording, keeps every finished episode and says so; ``--resume`` then
records the episodes still missing; ``--overwrite`` replaces an existing dataset.
``meta/colorsort.json`` keeps the settings, the episode number (seed - base seed) of each
dataset episode in order (``episodes``), every episode number tried and why failed ones failed.

Exit status: 0 done, 1 nothing kept or a worker failed, 2 bad arguments, 130 interrupted.
"""

from __future__ import annotations

import sys

from tqdm import tqdm

from colorsort.cell.cameras import parse_cameras
from colorsort.cli.args import parse_image_size
from colorsort.cli.config_args import Spelling, parse_config
from colorsort.cli.run import guarded
from colorsort.data.collect import CollectSummary, collect
from colorsort.data.config import CollectConfig
from colorsort.data.perturbations import PERTURBATIONS
from colorsort.errors import FAILED, INTERRUPTED, ConfigError
from colorsort.expert.config import parse_changes
from colorsort.logs import quiet_robosuite_info
from colorsort.variants import VARIANTS

# flags as they were written before the command was its configuration (docs/data.md): both forms work
SPELLING = Spelling(
    renamed={"--no-turn": "--turn_to_box=false", "--workers": "--executor.workers", "--executor": "--executor.name",
             "--retries": "--executor.retries", "--address": "--executor.address"},
    values={"cameras": parse_cameras, "image_size": parse_image_size, "expert": parse_changes},
    members={name: ("perturbations", kind.parse) for name, kind in PERTURBATIONS.items()},
    joined=frozenset({"shift"}))  # --shift given twice combines, as colorsort-eval's does


def perturbation_flags() -> str:
    """The help's list of the demonstrator's perturbations, one flag each."""
    return "the demonstrator's perturbations, one flag each (or --perturbations=[NAME:VALUE,...]):\n" + "\n".join(
        f"  --{name.replace('_', '-')}={kind.metavar}  {kind.help}" for name, kind in PERTURBATIONS.items())


def parse_args(argv: list[str] | None) -> CollectConfig:
    """``argv`` as a ``CollectConfig``: every field a flag (``--help``); ``--variant`` alone sets the variant's
    preset and robot."""
    argv = list(sys.argv[1:] if argv is None else argv)
    given = {a.partition("=")[0].replace("-", "_") for a in argv if a.startswith("--")}
    if "__variant" in given:
        if given & {"__preset", "__robot"}:
            raise ConfigError("--variant sets the preset and robot: give --variant alone, or --preset/--robot")
        at = next(i for i, a in enumerate(argv) if a.partition("=")[0] == "--variant")
        name = argv[at].partition("=")[2] or (argv[at + 1] if at + 1 < len(argv) else "")
        if name in VARIANTS:
            argv += [f"--preset={VARIANTS[name].preset}", f"--robot={VARIANTS[name].robot}"]
    return parse_config(CollectConfig, argv, prog="colorsort-collect", description=__doc__, spelling=SPELLING,
                        epilog=perturbation_flags())


def print_summary(config: CollectConfig, s: CollectSummary) -> None:
    reasons = ", ".join(f"{k}: {v}" for k, v in sorted(s.not_kept.items())) or "none"
    print(f"episodes this run: tried {s.tried}, kept {s.kept}, not kept {s.tried - s.kept} ({reasons})")
    print(f"recorded {s.sim_time_s:.1f} s of sim time in {s.wall_s:.1f} s: {s.real_time_factor:.2f}x real time")
    kept = f", {s.shards_kept} kept from the killed run" if s.shards_kept else ""
    print(f"shards: {s.shards} of at most {config.shard_size} episodes on {config.executor.workers} {s.executor} "
          f"worker{'s' * (config.executor.workers > 1)}{kept}; retried {s.retried}")
    if s.dataset_episodes:
        print(f"dataset: {s.root}  ({s.dataset_episodes} episodes, {s.dataset_frames} frames at {config.fps} fps, "
              f"{s.size_mb:.1f} MB on disk)")
        print("load it:  HF_HUB_OFFLINE=1 python -c \"from lerobot.datasets.lerobot_dataset import LeRobotDataset; "
              f"print(LeRobotDataset('{config.repo_id}', root='{s.root}', video_backend='pyav'))\"")
    if s.interrupted:
        print("interrupted: every finished episode is saved; run again with --resume to record the rest")


@guarded("colorsort-collect")
def main(argv: list[str] | None = None) -> int:
    quiet_robosuite_info()
    config = parse_args(argv)
    summary = collect(config, progress=True, log=tqdm.write)
    print_summary(config, summary)
    for error in summary.errors:
        print(f"a worker failed:\n{error}", file=sys.stderr)
    if summary.interrupted:
        return INTERRUPTED
    if summary.errors or summary.dataset_episodes == 0:
        return FAILED
    return 0


if __name__ == "__main__":
    sys.exit(main())
