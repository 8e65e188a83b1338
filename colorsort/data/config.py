"""What the collector records and where: ``CollectConfig``, validated on construction."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

from colorsort.cell.cameras import CAMERAS, DEFAULT_CAMERAS, DEFAULT_IMAGE_SIZE
from colorsort.config import PRESETS, TaskConfig, check_range, make_config
from colorsort.data.perturbations import Perturbation, canonical
from colorsort.errors import ConfigError, UnknownName
from colorsort.executors.base import DEFAULT_SHARD_SIZE, ExecutorConfig
from colorsort.expert.config import ExpertConfig, recording_expert
from colorsort.robots import get_robot
from colorsort.shifts.registry import parse_shifts, shift_label, training_shifts
from colorsort.variants import get_variant

FPS_CHOICES = (10, 20, 25, 50)  # control rates whose period is a whole number of 10 ms servo periods
VCODECS = ("h264", "libsvtav1", "hevc")


def check_vcodec(vcodec: str) -> None:
    """ConfigError naming the valid codecs unless ``vcodec`` is one of ``VCODECS``."""
    if vcodec not in VCODECS:
        raise UnknownName("vcodec", vcodec, list(VCODECS), "codecs")


@dataclass(frozen=True)
class CollectConfig:
    """What to record and where."""

    episodes: int = 10  # episodes to try; episode i runs with env seed `seed + i`
    boxes_per_episode: int = 1  # an episode ends when this many boxes have left the belt
    preset: str = "default"  # task preset (config.PRESETS)
    robot: str = "IRB140"  # "IRB140", "Panda" or "UR5e"
    variant: str | None = None  # record a benchmark variant's task (its preset, overrides, robot and lights)
    seed: int = 0  # base seed
    out: str = "datasets/colorsort"  # dataset directory (LeRobot's `root`)
    repo_id: str = "local/colorsort"  # LeRobot repo id, for loading: LeRobotDataset(repo_id, root=out)
    cameras: tuple[str, ...] = DEFAULT_CAMERAS  # stored as observation.images.<camera>; () records state only
    image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE  # (height, width) of every camera [px]
    fps: int = 20  # frames per second = the env's control rate [Hz]
    # which engine records the shards and how many at once (--executor.name local or ray, --executor.workers N)
    executor: ExecutorConfig = field(default_factory=ExecutorConfig)
    shard_size: int = DEFAULT_SHARD_SIZE  # episodes per shard, at most (fewer where needed to busy every worker)
    vcodec: str = "h264"  # video codec of the camera streams (bench_collect.py --vcodec compares them)
    # the demonstrator's perturbations (data.perturbations: late_pass, late_pick, brightness); kept in name order
    perturbations: tuple[Perturbation, ...] = ()
    turn_to_box: bool = True  # the expert turns the cup to a turned box; False: it keeps its home yaw (ExpertConfig)
    # the expert's settings changed from its belt's preset, (name, value) pairs (expert.config.CHANGEABLE)
    expert: tuple[tuple[str, float], ...] = ()
    # shifts' training ranges the episodes are recorded with (colorsort.shifts): "NAME:train,..." or "all:train";
    # a held-out level (1-3) is refused
    shift: str = ""
    resume: bool = False  # add the episodes still missing to an existing dataset
    overwrite: bool = False  # replace an existing dataset

    def __post_init__(self) -> None:
        if self.variant is not None:
            v = get_variant(self.variant)
            if (self.preset, self.robot) != (v.preset, v.robot):
                raise ConfigError(f"variant {self.variant!r} sets the preset ({v.preset!r}) and robot ({v.robot!r}); "
                                 f"got preset={self.preset!r}, robot={self.robot!r}: give the variant alone")
        if self.preset not in PRESETS:
            raise UnknownName("preset", self.preset, sorted(PRESETS), "presets")
        get_robot(self.robot)
        bad = [c for c in self.cameras if c not in CAMERAS]
        if bad or len(set(self.cameras)) != len(self.cameras):
            raise ConfigError(f"cameras={self.cameras}: give distinct names from {list(CAMERAS)}, or none")
        if self.fps not in FPS_CHOICES:
            raise ConfigError(f"fps={self.fps} not supported. Valid values: {list(FPS_CHOICES)}")
        check_vcodec(self.vcodec)
        check_range("episodes", self.episodes, 1, 1_000_000)
        check_range("boxes_per_episode", self.boxes_per_episode, 1, 100)
        check_range("shard_size", self.shard_size, 1, 100_000)
        object.__setattr__(self, "perturbations", canonical(self.perturbations))
        variant = get_variant(self.variant) if self.variant else None
        for p in self.perturbations:
            if not p.applies_to(variant, self.task_config.tracking):
                raise ConfigError(p.refusal(variant))
        if not all(16 <= s <= 1024 and s % 2 == 0 for s in self.image_size):
            raise ConfigError(f"image_size={self.image_size}: height and width must be even, in [16, 1024] px")
        if self.seed < 0:
            raise ConfigError(f"seed={self.seed} must be >= 0")
        self.expert_config  # noqa: B018 - validates the expert's changes
        training_shifts(self.shift, "shift")
        if self.resume and self.overwrite:
            raise ConfigError("Pass --resume or --overwrite, not both")

    def settings(self) -> dict:
        """The settings every episode of one dataset must share (checked on --resume)."""
        keys = ("boxes_per_episode", "preset", "robot", "variant", "seed", "repo_id", "cameras", "image_size", "fps",
                "vcodec")
        settings = {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items() if k in keys}
        if not self.turn_to_box:  # recorded only when off: datasets from before the option resume as they did
            settings["turn_to_box"] = False
        if self.expert:  # the same: recorded only when set
            settings["expert"] = [list(pair) for pair in self.expert]
        if self.shift:  # the same
            settings["shift"] = shift_label(parse_shifts(self.shift))
        settings.update({p.name: p.settings() for p in self.perturbations})
        return settings

    @property
    def expert_config(self) -> ExpertConfig:
        """The expert that records: its belt's preset, ``turn_to_box`` and the ``expert`` changes."""
        return recording_expert(self.task_config.tracking, self.turn_to_box, self.expert)

    @property
    def task_config(self) -> TaskConfig:
        """The task the episodes run: the variant's, or the preset's."""
        return get_variant(self.variant).task_config if self.variant else make_config(self.preset)

