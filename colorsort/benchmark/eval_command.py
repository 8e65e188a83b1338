"""``colorsort-eval``'s settings as one typed configuration: what the command parses its flags into, and what the
training pipeline builds to run it (``argv``) and keys its evaluations' cache on (``settings``)."""

from __future__ import annotations

import builtins
from dataclasses import dataclass, field
from typing import Any

from colorsort.benchmark.lockstep import PRECISIONS
from colorsort.config import BACKENDS
from colorsort.errors import ConfigError
from colorsort.executors.base import DEFAULT_SHARD_SIZE, ExecutorConfig
from colorsort.shifts import LEVELS


@dataclass(frozen=True)
class ReportConfig:
    """``--report.*``: the page a browser opens from disk."""

    dir: str | None = None  # write a report page here: DIR/index.html, its videos and DIR/report.json
    # episodes filmed per variant, failures first (None: every failure and 3 successes; 0: none)
    videos: int | None = None
    overwrite: bool = False  # replace an existing report folder

    def __post_init__(self) -> None:
        if self.videos is not None and self.videos < 0:
            raise ConfigError(f"--videos {self.videos}: give 0 or more (--report.videos)")
        if self.videos is not None and self.dir is None:
            raise ConfigError("--videos: films go into a report; give --report DIR (--report.dir)")


@dataclass(frozen=True)
class SweepConfig:
    """``--sweep.*``: the control and every shift at every level on the same seeds, one table."""

    run: bool = False  # run the sweep (--sweep) instead of one evaluation
    shifts: tuple[str, ...] = ()  # the shifts to sweep (default: every shift); --sweep-shifts
    levels: tuple[int, ...] = (1, 2, 3)  # the levels to sweep; --levels
    side_episodes: int | None = None  # episodes at levels other than 2 (default: --episodes); --side-episodes

    def __post_init__(self) -> None:
        if not self.levels or any(v not in LEVELS[1:] for v in self.levels):
            raise ConfigError(f"--levels {','.join(map(str, self.levels))}: give comma-separated levels from "
                              f"{list(LEVELS[1:])}")


@dataclass(frozen=True)
class EvalCommandConfig:
    """``colorsort-eval``'s settings: every field is a flag (``--episodes 50``, ``--report.dir=DIR``)."""

    policy: str = "expert"  # expert, random, or a LeRobot checkpoint folder
    variant: str = "default"  # a variant name (see --list), or all
    episodes: int = 10  # episodes to run
    seed: int | None = None  # first seed (default: the variant's evaluation seeds)
    image_size: int | None = None  # square camera images [px] (default: a checkpoint's own, else 128)
    # comma-separated cameras or 'none' (default: those a checkpoint was trained on, else scene,wrist)
    cameras: str | None = None
    episode_length: int | None = None  # steps before an episode is truncated (default: the variant's time limit)
    # where the episodes run and how many at once (--envs N is --executor.workers N; --executor ray is
    # --executor.name ray): each in its own process or Ray task, the same numbers whatever N
    executor: ExecutorConfig = field(default_factory=ExecutorConfig)
    shard_size: int = DEFAULT_SHARD_SIZE  # episodes per job, at most (fewer where that keeps every worker busy)
    # CPU cells each worker steps together, one batched policy forward a control step (--envs W: W x N cells)
    batch_size: int = 1
    # a learned policy's forward: float32, or bfloat16 (CPU autocast, --batch-size above 1; docs/speed.md says where
    # its scores hold); the printout and --json say which
    precision: str = "float32"
    json: str | None = None  # write the metrics as JSON here; each finished episode is kept in <json>.partial.jsonl
    resume: bool = False  # run only the episodes the journal of --json (<json>.partial.jsonl) lacks
    backend: str = "cpu"  # cpu: the CPU cell (the reference); warp: the batched cell on MuJoCo Warp (docs/gpu.md)
    device: str | None = None  # --backend warp: Warp's device, cuda:0 (default) or cpu
    # held-out shifts NAME:LEVEL, level 0-3, or NAME:train for a shift's training range (all:L: every shift; see
    # --list-shifts); --shift given twice adds
    shift: tuple[str, ...] = ()
    report: ReportConfig = field(default_factory=ReportConfig)
    sweep: SweepConfig = field(default_factory=SweepConfig)
    list: bool = False  # print the variants, one per line, and exit
    list_shifts: bool = False  # print every held-out shift, its levels in units and its training range, and exit

    def __post_init__(self) -> None:
        if self.episodes < 1:
            raise ConfigError(f"--episodes {self.episodes}: give at least 1")
        if self.backend not in BACKENDS:
            raise ConfigError(f"--backend {self.backend!r}: valid backends are {list(BACKENDS)}")
        if self.device is not None and self.backend != "warp":
            raise ConfigError("--device: only --backend warp runs on a chosen device")
        if self.backend == "warp" and self.executor.name != "local":
            raise ConfigError("--backend warp runs on one device, not on an --executor")
        if self.sweep.run and (self.shift or self.report.dir or self.variant == "all" or self.backend != "cpu"):
            raise ConfigError("--sweep runs its own arms on one variant, on the CPU cell: leave out --shift, --report,"
                              " --variant all and --backend warp")
        if self.resume and not self.json:
            raise ConfigError("--resume continues a run from the journal beside its --json: give --json")
        if not 1 <= self.batch_size <= 1024:
            raise ConfigError(f"--batch-size {self.batch_size}: give 1 to 1024 cells a worker")
        if self.batch_size > 1 and self.backend != "cpu":
            raise ConfigError("--batch-size steps CPU cells in each worker (--backend cpu); with --backend warp, "
                              "--envs is the number of worlds stepped together")
        if self.precision not in PRECISIONS:
            raise ConfigError(f"--precision {self.precision!r}: valid precisions are {list(PRECISIONS)}")
        if self.precision != "float32" and (self.batch_size == 1 or self.policy in ("expert", "random")):
            raise ConfigError(f"--precision {self.precision}: a learned policy's batched forward only; give "
                              "--batch-size 2 or more and a checkpoint")

    def settings(self) -> dict[str, Any]:
        """What the episodes' numbers depend on beside the policy: the key of an evaluation's cache (not where the
        episodes run, nor the output files)."""
        return {"variant": self.variant, "episodes": self.episodes, "seed": self.seed, "image_size": self.image_size,
                "cameras": self.cameras, "episode_length": self.episode_length, "shift": list(self.shift),
                "batch_size": self.batch_size, "precision": self.precision}

    def argv(self) -> builtins.list[str]:  # the class has a field named list
        """The flags of a single evaluation that parse back into this configuration (its sweep and report left out:
        a pipeline runs neither)."""
        if self.sweep != SweepConfig() or self.report != ReportConfig():
            raise ConfigError("argv() writes a single evaluation's flags: no --sweep, no --report")
        optional = {"--seed": self.seed, "--image-size": self.image_size, "--cameras": self.cameras,
                    "--episode-length": self.episode_length, "--json": self.json, "--device": self.device}
        return (["--policy", self.policy, "--variant", self.variant, "--episodes", str(self.episodes)]
                + [a for flag, value in optional.items() if value is not None for a in (flag, str(value))]
                + ["--envs", str(self.executor.workers), "--shard-size", str(self.shard_size),
                   "--batch-size", str(self.batch_size), "--precision", self.precision, "--backend", self.backend]
                + (["--executor", self.executor.name] if self.executor.name != "local" else [])
                + [a for s in self.shift for a in ("--shift", s)] + (["--resume"] if self.resume else []))
