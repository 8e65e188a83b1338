"""Evaluate a policy on a benchmark variant: success rate with a confidence interval and sorting metrics.

Example::

    colorsort-eval --policy expert --variant default --episodes 50 --envs 2 --json outputs/eval.json
    colorsort-eval --policy outputs/train/act/checkpoints/last/pretrained_model --variant jitter --episodes 20
    colorsort-eval --policy expert --variant all --episodes 50 --executor ray --envs 8
    colorsort-eval --policy baselines/act-state --variant distractors --episodes 10 --report outputs/report
    colorsort-eval --policy baselines/act-state --variant default --episodes 4096 --seed 0 --backend warp --envs 4096
    colorsort-eval --list
    colorsort-eval --policy baselines/act-camera-snapshot --variant default --shift camera-pose:2 --episodes 50
    colorsort-eval --list-shifts
    colorsort-eval --policy expert --variant default --sweep --episodes 50 --side-episodes 20 --json outputs/sweep.json

Episode ``k`` runs with the variant's ``k``-th evaluation seed (or ``--seed S`` + k), so the same
command gives the same numbers, whatever ``--envs`` (episodes run at once), ``--executor`` (local
processes, or a Ray cluster: a local one, or the one at ``--address``) and ``--shard-size``
(episodes per job; each job builds one env and one policy). ``--variant all`` runs every
variant the policy fits (a checkpoint fits those with its robot's state and action sizes) and
prints one line per variant.
Metrics: success rate (every box of the episode where it belongs, none misplaced or dropped) with a
95% Wilson interval; boxes placed correctly, misplaced, dropped;
distractors (boxes with no bin) let through; boxes per minute (boxes handled right, placed in
their bin or let through, per minute of sim time); mean cycle time (sim time between consecutive
boxes handled right).
``--report DIR`` writes a page that a browser opens from disk (``DIR/index.html``): success per
variant, every episode's boxes, failures first, with a video of the scene camera per filmed
episode (``--videos N`` per variant, failures first; default every failure and 3 successes),
and ``DIR/report.json`` (what ``--json`` writes). Filming changes no result.
``--backend warp`` runs the episodes on the batched cell (MuJoCo Warp, the ``gpu`` extra; ``--device``
cuda:0 by default, cpu for Warp's CPU device), ``--envs`` worlds at once in waves, the policy on the
same device; it writes the same report and JSON, its films drawn from the worlds' recorded states by the CPU
cell's renderer (docs/gpu.md).
``--shift NAME:LEVEL`` (repeatable; ``all:L`` for every shift at once) evaluates under held-out shifts
(docs/shifts.md) on the shift evaluation seeds (30000 on); the printout, ``--json`` and ``--report`` name the
shift, and each episode's record holds the values drawn for it. ``--sweep`` runs the control and every shift at
every level on the same seeds (``--episodes`` for the control and level 2, ``--side-episodes`` for levels 1 and 3)
and prints one table (``--json``: every arm's report and the table's rows).
Exit status 0 when it ran, 1 when it failed or was interrupted, 2 for bad arguments.
"""

from __future__ import annotations

import argparse
import json
import shlex
import shutil
import sys
import time
from dataclasses import asdict
from datetime import UTC, datetime
from pathlib import Path

from colorsort.benchmark.evaluate import Evaluation, observation_settings, run_evaluation
from colorsort.benchmark.metrics import format_report, format_table
from colorsort.benchmark.policies import misfit
from colorsort.benchmark.report_page import SUCCESSES_FILMED, choose_films, write_report
from colorsort.benchmark.shift_sweep import format_sweep, run_sweep, sweep_arms, sweep_rows
from colorsort.cli.run import guarded
from colorsort.errors import ConfigError
from colorsort.executors.base import DEFAULT_SHARD_SIZE, EXECUTORS, ExecutorConfig
from colorsort.logs import quiet_robosuite_info
from colorsort.results import machine
from colorsort.shifts import GROUPS, LEVELS, SHIFTS, parse_shifts
from colorsort.variants import SHIFT_SEEDS, VARIANTS, get_variant

BACKENDS = ("cpu", "warp")  # the warp backend is imported only when chosen: the default install has no warp


@guarded("colorsort-eval")
def main(argv: list[str] | None = None) -> int:
    quiet_robosuite_info()
    parser = argparse.ArgumentParser(prog="colorsort-eval", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--policy", default="expert", help="expert, random, or a LeRobot checkpoint folder")
    parser.add_argument("--variant", default="default", help="a variant name (see --list), or all")
    parser.add_argument("--episodes", type=int, default=10, help="episodes to run")
    parser.add_argument("--seed", type=int, default=None, help="first seed (default: the variant's seeds)")
    parser.add_argument("--image-size", type=int, default=None,
                        help="square camera images [px] (default: a checkpoint's own, else 128)")
    parser.add_argument("--cameras", default=None,
                        help="comma-separated cameras or 'none' (default: those a checkpoint was trained on, "
                             "else scene,wrist)")
    parser.add_argument("--episode-length", type=int, default=None,
                        help="steps before an episode is truncated (default: the variant's time limit)")
    parser.add_argument("--envs", type=int, default=1,
                        help="episodes run at once, each in its own process or Ray task (same numbers whatever N)")
    parser.add_argument("--executor", default="local", choices=EXECUTORS,
                        help="local: processes on this machine; ray: a Ray cluster (see --address)")
    parser.add_argument("--address", default=None,
                        help="ray: the cluster to join, e.g. auto (default: start one on this machine)")
    parser.add_argument("--shard-size", type=int, default=DEFAULT_SHARD_SIZE,
                        help="episodes per job, at most (fewer where that keeps every worker busy)")
    parser.add_argument("--retries", type=int, default=2, help="times a job runs again after its process died")
    parser.add_argument("--json", default=None, help="write the metrics as JSON here")
    parser.add_argument("--report", default=None,
                        help="write a report page here: DIR/index.html, its videos and DIR/report.json")
    parser.add_argument("--videos", type=int, default=None,
                        help="--report: episodes filmed per variant, failures first (default: every failure and "
                             f"{SUCCESSES_FILMED} successes; 0: none)")
    parser.add_argument("--overwrite", action="store_true", help="--report: replace an existing report folder")
    parser.add_argument("--backend", default="cpu", choices=BACKENDS,
                        help="cpu: the CPU cell (the reference); warp: the batched cell on MuJoCo Warp (docs/gpu.md)")
    parser.add_argument("--device", default=None,
                        help="--backend warp: Warp's device, cuda:0 (default) or cpu")
    parser.add_argument("--shift", action="append", default=None, metavar="NAME:LEVEL",
                        help="a held-out shift at a level 0-3, repeatable (all:L: every shift); see --list-shifts")
    parser.add_argument("--sweep", action="store_true",
                        help="the control and every shift at every level, on the same seeds: one table")
    parser.add_argument("--sweep-shifts", default=None,
                        help="--sweep: comma-separated shifts to sweep (default: every shift)")
    parser.add_argument("--levels", default="1,2,3", help="--sweep: comma-separated levels (default: 1,2,3)")
    parser.add_argument("--side-episodes", type=int, default=None,
                        help="--sweep: episodes at levels other than 2 (default: --episodes)")
    parser.add_argument("--list", action="store_true", help="print the variants, one per line, and exit")
    parser.add_argument("--list-shifts", action="store_true",
                        help="print every held-out shift, its group and levels in units, and exit")
    args = parser.parse_args(argv)
    if args.list:
        for v in VARIANTS.values():
            print(f"{v.name:<14} {v.gym_id:<34} {v.description}")
        return 0
    if args.list_shifts:
        print(list_shifts())
        return 0
    if args.episodes < 1:
        parser.error(f"--episodes {args.episodes}: give at least 1")
    if args.envs < 1:
        parser.error(f"--envs {args.envs}: give at least 1")
    if args.videos is not None and args.videos < 0:
        parser.error(f"--videos {args.videos}: give 0 or more")
    if args.videos is not None and args.report is None:
        parser.error("--videos: films go into a report; give --report DIR")
    if args.report and Path(args.report).exists() and any(Path(args.report).iterdir()) and not args.overwrite:
        parser.error(f"--report {args.report} exists and is not empty; pass --overwrite to replace it")
    if args.device is not None and args.backend != "warp":
        parser.error("--device: only --backend warp runs on a chosen device")
    if args.backend == "warp" and args.executor != "local":
        parser.error("--backend warp runs on one device, not on an --executor")
    shift = tuple(str(s) for s in parse_shifts(args.shift))  # ValueError (exit 2) naming the valid shifts
    if args.sweep and (shift or args.report or args.variant == "all" or args.backend != "cpu"):
        parser.error("--sweep runs its own arms on one variant, on the CPU cell: leave out --shift, --report, "
                     "--variant all and --backend warp")
    if args.backend == "warp" and any(not s.endswith(":0") for s in shift):
        raise ConfigError(f"--backend warp: the batched cell applies no held-out shift yet (asked: {', '.join(shift)});"
                          " run them on the CPU cell (--backend cpu)")
    executor = ExecutorConfig(args.executor, args.envs, args.retries, args.address)
    cameras, image_size = observation_settings(args.policy, args.cameras, args.image_size)
    names = variant_names(args.policy, args.variant)
    if args.sweep:
        return sweep(args, cameras, image_size, executor)
    film = args.report is not None and args.videos != 0
    if args.backend == "warp":
        try:
            from colorsort.batched.evaluate import evaluate_batched
        except ImportError as error:
            raise ConfigError(f"--backend warp needs MuJoCo Warp ({error}): pip install -e '.[gpu]'") from error

        batched = [evaluate_batched(args.policy, name, args.episodes, seed=args.seed, envs=args.envs,
                                    device=args.device or "cuda:0", episode_length=args.episode_length, film=film,
                                    videos=args.videos) for name in names]
        evaluation = Evaluation([b.report for b in batched],
                                {(b.report.variant, seed): video for b in batched for seed, video in b.films.items()})
    else:
        evaluation = run_evaluation(args.policy, names, args.episodes, seed=args.seed, image_size=image_size,
                                    cameras=cameras, episode_length=args.episode_length, executor=executor,
                                    shard_size=args.shard_size, film=film, shift=shift)
    reports = evaluation.reports
    print(format_report(reports[0]) if args.variant != "all" else f"policy {args.policy}\n" + format_table(reports))
    found = [asdict(r) for r in reports]
    payload = found if args.variant == "all" else found[0]
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(payload, indent=1))
        print(f"metrics: {args.json}")
    if args.report:
        if args.overwrite:
            shutil.rmtree(args.report, ignore_errors=True)
        kept = choose_films(reports, evaluation.films, args.videos)
        command = shlex.join(["colorsort-eval", *(sys.argv[1:] if argv is None else argv)])
        page = write_report(args.report, reports, kept, payload, command)
        print(f"report: {page} ({len(kept)} videos)")
    return 0


def list_shifts() -> str:
    """Every held-out shift: group, name, what changes, and its levels 1-3 in units."""
    lines = []
    for group in GROUPS:
        for shift in (s for s in SHIFTS.values() if s.group == group):
            lines.append(f"{group:<11} {shift.name:<18} {shift.summary}")
            lines += [f"{'':<11} {'':<18}   level {lv}: {shift.level_text(lv)}" for lv in LEVELS]
            train = ("drawn per episode between as built and level 1 (exclusive)" if shift.trainable
                     else "none: held out wholly")
            lines.append(f"{'':<11} {'':<18}   train:   {train}")
    lines.append(f"{'':<11} {'all:L':<18} every shift above at level L at once (all:train: every training range)")
    return "\n".join(lines)


def sweep(args: argparse.Namespace, cameras: tuple[str, ...], image_size: tuple[int, int],
          executor: ExecutorConfig) -> int:
    """``--sweep``: the control and every shift at every level on the same seeds; prints the table."""
    levels = tuple(int(v) for v in args.levels.split(",") if v.strip().isdigit())
    if not levels or len(levels) != len([v for v in args.levels.split(",") if v.strip()]):
        raise ConfigError(f"--levels {args.levels!r}: give comma-separated levels from {list(LEVELS[1:])}")
    names = tuple(n.strip() for n in args.sweep_shifts.split(",") if n.strip()) if args.sweep_shifts else None
    arms = sweep_arms(args.episodes, args.side_episodes or args.episodes, levels, names)
    start = time.perf_counter()
    reports = run_sweep(args.policy, args.variant, arms, image_size=image_size, cameras=cameras,
                        episode_length=args.episode_length, executor=executor, shard_size=args.shard_size)
    wall = time.perf_counter() - start
    rows = sweep_rows(reports)
    print(format_sweep(args.policy, args.variant, rows))
    print(f"{sum(a.episodes for a in arms)} episodes in {wall / 60:.1f} min ({args.executor}, {args.envs} envs)")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        payload = {"policy": args.policy, "variant": args.variant, "seeds": list(SHIFT_SEEDS[: args.episodes]),
                   "command": shlex.join(["colorsort-eval", *sys.argv[1:]]), "wall_s": round(wall, 1),
                   "executor": args.executor, "envs": args.envs, "machine": machine(),
                   "written": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
                   "rows": rows, "reports": [asdict(r) for r in reports]}
        Path(args.json).write_text(json.dumps(payload, indent=1))
        print(f"metrics: {args.json}")
    return 0


def variant_names(policy: str, variant: str) -> list[str]:
    """``[variant]``, or for ``all`` every variant the policy fits (the others are named on stderr)."""
    if variant != "all":
        reason = misfit(policy, get_variant(variant))
        if reason:
            fits = [v.name for v in VARIANTS.values() if not misfit(policy, v)]
            raise ConfigError(f"{policy} cannot run on {variant}: {reason}; variants it fits: {fits}")
        return [variant]
    names = []
    for v in VARIANTS.values():
        reason = misfit(policy, v)
        if reason:
            print(f"colorsort-eval: skipping {v.name}: {reason}", file=sys.stderr)
        else:
            names.append(v.name)
    return names


if __name__ == "__main__":
    sys.exit(main())
