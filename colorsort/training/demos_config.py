"""A recipe's ``demos`` section: the expert's demos a baseline learns from."""

from __future__ import annotations

from dataclasses import dataclass

from colorsort.cell.cameras import check_cameras
from colorsort.data.perturbations import Perturbation, canonical
from colorsort.errors import ConfigError
from colorsort.expert.config import changed, expert_preset
from colorsort.shifts.registry import training_shifts
from colorsort.variants import get_variant


def at_least_one(section: object, *names: str) -> None:
    """ConfigError unless each field ``names`` of ``section`` is at least 1."""
    for name in names:
        if getattr(section, name) < 1:
            raise ConfigError(f"{name}={getattr(section, name)}: give at least 1")


@dataclass(frozen=True)
class DemosConfig:
    """The expert's demos a baseline learns from (``colorsort-collect`` once per training variant, merged)."""

    # (variant, weight) pairs: each demo count is split over the variants in proportion.
    train_mix: tuple[tuple[str, float], ...] = (("default", 1.0), ("jitter", 1.0), ("fast", 1.0),
                                                ("distractors", 1.0))
    # increasing demo counts; the largest trains the shipped policy.
    counts: tuple[int, ...] = (8, 40, 200)
    # boxes that leave the belt in one demo.
    boxes_per_episode: int = 3
    # (variant, boxes) pairs for training variants whose demos hold another number of boxes.
    boxes_by_variant: tuple[tuple[str, int], ...] = ()
    # cameras recorded and read by the policy; () for a policy that reads the box state instead.
    cameras: tuple[str, ...] = ()
    # square camera images [px].
    image_size: int = 64
    # the demonstrator's perturbations (``colorsort.data.perturbations``), each given to the training variants it
    # applies to.
    perturbations: tuple[Perturbation, ...] = ()
    # the expert turns the cup to a turned box; False: it keeps its home yaw.
    turn_to_box: bool = True
    # the expert's settings changed from its belt's preset, (name, value) pairs of ``ExpertConfig`` fields
    # (``colorsort.expert.config.CHANGEABLE``), for the demos and DAgger's labels alike, e.g.
    # press:0.01,track_hold_time:0.15.
    expert: tuple[tuple[str, float], ...] = ()
    # held-out shifts' training ranges every demo is recorded with, drawn per episode (``colorsort.shifts``), e.g.
    # all:train; a held-out level (1-3) is refused, naming it.
    shift: str = ""

    def __post_init__(self) -> None:
        training_shifts(self.shift, "demos.shift")  # ConfigError naming a held-out level
        for variant in self.train_variants:
            get_variant(variant)  # ConfigError naming the valid variants
        if not self.train_mix or any(w <= 0 for _, w in self.train_mix):
            raise ConfigError(f"train_mix={self.train_mix}: give one or more variants, each a weight above 0")
        if (not self.counts or list(self.counts) != sorted(set(self.counts))
                or any(n < len(self.train_mix) for n in self.counts)):
            raise ConfigError(f"counts={self.counts}: give increasing demo counts, each at least the number of "
                              f"training variants ({len(self.train_mix)})")
        for variant, boxes in self.boxes_by_variant:
            get_variant(variant)
            if boxes < 1:
                raise ConfigError(f"boxes_by_variant has ({variant!r}, {boxes}): give at least 1 box")
        at_least_one(self, "boxes_per_episode", "image_size")
        check_cameras(self.cameras)
        for tracking in {get_variant(v).task_config.tracking for v in self.train_variants}:
            changed(expert_preset(tracking), self.expert)  # ConfigError naming the valid settings
        object.__setattr__(self, "perturbations", canonical(self.perturbations))
        for p in self.perturbations:
            if not self.applying(p):
                raise ConfigError(f"{p.refusal(None)}; train_mix {list(self.train_variants)} has no variant it "
                                  f"applies to")

    @property
    def train_variants(self) -> tuple[str, ...]:
        return tuple(v for v, _ in self.train_mix)

    def applying(self, p: Perturbation) -> tuple[str, ...]:
        """The training variants perturbation ``p`` acts on."""
        return tuple(v for v in self.train_variants
                     if p.applies_to(get_variant(v), get_variant(v).task_config.tracking))

    def perturbations_on(self, variant: str) -> tuple[Perturbation, ...]:
        """The perturbations ``variant``'s demos are recorded with."""
        return tuple(p for p in self.perturbations if variant in self.applying(p))

    def split(self, n: int) -> dict[str, int]:
        """``n`` demos over ``train_mix`` in proportion to the weights (largest remainders round up)."""
        total = sum(w for _, w in self.train_mix)
        exact = [n * w / total for _, w in self.train_mix]
        counts = [int(x) for x in exact]
        for k in sorted(range(len(exact)), key=lambda k: counts[k] - exact[k])[: n - sum(counts)]:
            counts[k] += 1
        return {v: c for v, c in zip(self.train_variants, counts, strict=True)}

    def boxes(self, variant: str) -> int:
        """Boxes in each demo of training variant ``variant``."""
        return dict(self.boxes_by_variant).get(variant, self.boxes_per_episode)
