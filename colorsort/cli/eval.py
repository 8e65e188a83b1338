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
    colorsort-eval --policy baselines/act-camera-tracking --variant tracking --episodes 50 --envs 2 --batch-size 8

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
``--batch-size N`` steps N cells in each worker together, one batched forward of a checkpoint a control step
(``benchmark/lockstep.py``; docs/benchmark.md); the same episodes up to a forward's rounding.
With ``--json``, each finished episode (of a run or a sweep) is written to ``<json>.partial.jsonl`` as it arrives;
Ctrl-C stops within about one episode and says how many it kept, and ``--resume`` runs only the episodes it lacks.
Exit status 0 when it ran, 1 when it failed, 2 for bad arguments, 130 when interrupted.
"""

from __future__ import annotations

import json
import shlex
import shutil
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict
from datetime import UTC, datetime
from pathlib import Path

from colorsort.benchmark.eval_command import EvalCommandConfig
from colorsort.benchmark.evaluate import Evaluation, observation_settings, run_evaluation
from colorsort.benchmark.metrics import format_report, format_table
from colorsort.benchmark.policies import misfit
from colorsort.benchmark.report_page import choose_films, write_report
from colorsort.benchmark.shift_sweep import format_sweep, run_sweep, sweep_arms, sweep_rows
from colorsort.benchmark.sweep_journal import SweepJournal, header, journal_path
from colorsort.cli.config_args import Spelling, parse_config
from colorsort.cli.run import guarded
from colorsort.errors import ConfigError, Interrupted
from colorsort.executors.base import ExecutorConfig
from colorsort.logs import quiet_robosuite_info
from colorsort.results import this_machine
from colorsort.shifts import GROUPS, LEVELS, SHIFTS, parse_shifts
from colorsort.variants import SHIFT_SEEDS, VARIANTS, get_variant

# flags as they were written before the command was its configuration (docs/commands.md): both forms work
SPELLING = Spelling(renamed={"--envs": "--executor.workers", "--executor": "--executor.name",
                             "--address": "--executor.address", "--retries": "--executor.retries",
                             "--report": "--report.dir", "--videos": "--report.videos",
                             "--overwrite": "--report.overwrite=true", "--sweep": "--sweep.run=true",
                             "--sweep-shifts": "--sweep.shifts", "--levels": "--sweep.levels",
                             "--side-episodes": "--sweep.side_episodes"})


def parse_args(argv: list[str]) -> EvalCommandConfig:
    """``argv`` as ``colorsort-eval``'s configuration; ``--help`` prints every field and exits."""
    return parse_config(EvalCommandConfig, argv, prog="colorsort-eval", description=__doc__, spelling=SPELLING)


@guarded("colorsort-eval")
def main(argv: list[str] | None = None) -> int:
    quiet_robosuite_info()
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    if args.list:
        for v in VARIANTS.values():
            print(f"{v.name:<14} {v.gym_id:<34} {v.description}")
        return 0
    if args.list_shifts:
        print(list_shifts())
        return 0
    report = args.report
    if report.dir and Path(report.dir).exists() and any(Path(report.dir).iterdir()) and not report.overwrite:
        raise ConfigError(f"--report {report.dir} exists and is not empty; pass --overwrite to replace it")
    shift = tuple(str(s) for s in parse_shifts(list(args.shift)))  # ValueError (exit 2) naming the valid shifts
    if args.backend == "warp" and any(not s.endswith(":0") for s in shift):
        raise ConfigError(f"--backend warp: the batched cell applies no held-out shift yet (asked: {', '.join(shift)});"
                          " run them on the CPU cell (--backend cpu)")
    executor = args.executor
    cameras, image_size = observation_settings(args.policy, args.cameras, args.image_size)
    names = variant_names(args.policy, args.variant)
    if args.sweep.run:
        return sweep(args, argv, cameras, image_size, executor)
    film = report.dir is not None and report.videos != 0
    journal = None
    if args.backend == "warp":
        evaluation = on_warp(args, names, film)
    else:
        journal = open_journal(args, cameras, image_size, "evaluation")
        with interrupted_line(journal):
            evaluation = run_evaluation(args.policy, names, args.episodes, seed=args.seed, image_size=image_size,
                                        cameras=cameras, episode_length=args.episode_length, executor=executor,
                                        shard_size=args.shard_size, film=film, shift=shift,
                                        batch_size=args.batch_size, precision=args.precision,
                                        done=journal.done if journal else None,
                                        on_episode=journal.add if journal else None)
    reports = evaluation.reports
    print(format_report(reports[0]) if args.variant != "all" else f"policy {args.policy}\n" + format_table(reports))
    if args.backend == "cpu":
        print(f"cells: {executor.workers} {executor.name} worker(s) x {cells_stepped(args)}")
    found = [{**asdict(r), "batch_size": args.batch_size, "precision": args.precision} for r in reports]
    payload = found if args.variant == "all" else found[0]
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(payload, indent=1))
        print(f"metrics: {args.json}")
        if journal is not None:
            journal.finish()
    if report.dir:
        if report.overwrite:
            shutil.rmtree(report.dir, ignore_errors=True)
        kept = choose_films(reports, evaluation.films, report.videos)
        command = shlex.join(["colorsort-eval", *argv])
        page = write_report(report.dir, reports, kept, payload, command)
        print(f"report: {page} ({len(kept)} videos)")
    return 0


def on_warp(args: EvalCommandConfig, names: list[str], film: bool) -> Evaluation:
    """The evaluation of ``names`` on the batched cell (``--backend warp``)."""
    try:
        from colorsort.batched.evaluate import evaluate_batched
    except ImportError as error:
        raise ConfigError(f"--backend warp needs MuJoCo Warp ({error}): pip install -e '.[gpu]'") from error

    batched = [evaluate_batched(args.policy, name, args.episodes, seed=args.seed, envs=args.executor.workers,
                                device=args.device or "cuda:0", episode_length=args.episode_length, film=film,
                                videos=args.report.videos) for name in names]
    return Evaluation([b.report for b in batched],
                      {(b.report.variant, seed): video for b in batched for seed, video in b.films.items()})


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


def sweep(args: EvalCommandConfig, argv: list[str], cameras: tuple[str, ...], image_size: tuple[int, int],
          executor: ExecutorConfig) -> int:
    """``--sweep``: the control and every shift at every level on the same seeds; prints the table."""
    arms = sweep_arms(args.episodes, args.sweep.side_episodes or args.episodes, args.sweep.levels,
                      args.sweep.shifts or None)
    journal = open_journal(args, cameras, image_size, "sweep")
    wanted = {key for a in arms for key in a.keys}
    reused = len(wanted & journal.done.keys()) if journal else 0
    if journal and reused:
        print(f"resuming: {reused} of the {len(wanted)} episodes finished already ({journal.path})")
    start = time.perf_counter()
    with interrupted_line(journal):
        reports = run_sweep(args.policy, args.variant, arms, image_size=image_size, cameras=cameras,
                            episode_length=args.episode_length, executor=executor, shard_size=args.shard_size,
                            done=journal.done if journal else None, on_episode=journal.add if journal else None,
                            batch_size=args.batch_size, precision=args.precision)
    wall = time.perf_counter() - start
    rows = sweep_rows(reports)
    print(format_sweep(args.policy, args.variant, rows))
    resumed = f" (and {reused} from the journal)" if reused else ""
    looped = args.policy in ("expert", "random") and args.batch_size == 1
    print(f"{len(wanted) - reused} episodes in {wall / 60:.1f} min{resumed} ({executor.name}, {executor.workers} envs"
          f"{'' if looped else ' x ' + cells_stepped(args)})")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        payload = {"policy": args.policy, "variant": args.variant, "seeds": list(SHIFT_SEEDS[: args.episodes]),
                   "command": shlex.join(["colorsort-eval", *argv]), "wall_s": round(wall, 1),
                   "executor": executor.name, "envs": executor.workers, "batch_size": args.batch_size,
                   "precision": args.precision, "machine": this_machine(),
                   "resumed_episodes": reused,  # taken from the journal; wall_s is the others' time
                   "written": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
                   "rows": rows, "reports": [asdict(r) for r in reports]}
        Path(args.json).write_text(json.dumps(payload, indent=1))
        print(f"metrics: {args.json}")
        if journal is not None:
            journal.finish()
    return 0


def cells_stepped(args: EvalCommandConfig) -> str:
    """What each worker steps: ``N stepped together`` and the forward's precision, or for the expert and ``random``
    (no forward to share) one env, whatever ``--batch-size``."""
    if args.policy in ("expert", "random"):
        return "1 env (the expert and random have no forward to share)"
    return f"{args.batch_size} stepped together; policy forward in {args.precision}"


def open_journal(args: EvalCommandConfig, cameras: tuple[str, ...], image_size: tuple[int, int],
                 kind: str) -> SweepJournal | None:
    """The journal beside ``--json`` (None without it): each finished episode written as it arrives, so an
    interrupted run resumes (``--resume``); one format for sweeps and plain runs, whose headers differ by ``kind``."""
    if not args.json:
        return None
    head = header(args.policy, args.variant, cameras, image_size, args.episode_length)
    if kind != "sweep":  # a sweep's header is as it always was: its journals stay resumable
        head["kind"] = kind
    if args.precision != "float32":
        head["precision"] = args.precision
    journal = SweepJournal(journal_path(args.json), head, args.resume)
    if journal.done and kind != "sweep":  # a sweep says how many of its own episodes it reuses
        print(f"resuming: {len(journal.done)} finished episodes in {journal.path}")
    return journal


@contextmanager
def interrupted_line(journal: SweepJournal | None) -> Iterator[None]:
    """Ctrl-C (``Interrupted``) said in one line on stderr, with where the finished episodes are, then exit 130."""
    try:
        yield
    except Interrupted as stop:
        kept = (f"{stop.finished} of {stop.total} episodes kept in {journal.path}; --resume continues" if journal
                else f"{stop.finished} of {stop.total} episodes finished; none kept (--json keeps each as it ends)")
        raise Interrupted(stop.finished, stop.total, kept) from None


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
