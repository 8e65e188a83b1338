"""Named recipes for the learned baselines: the demos, the LeRobot policy, its training and its evaluation.

A recipe is everything ``colorsort-baseline`` needs to rebuild a baseline, in sections as
``lerobot-train``'s configuration has them: ``demos`` (which variants the expert's demos come from and in
what proportion, the cameras recorded, the demonstrator's perturbations), ``policy`` (ACT or diffusion,
``policy_config``), ``training``, ``dagger`` (rounds of expert labels on the policy's own states, none by
default) and ``evaluation``. Each section is a frozen dataclass that checks its own
fields; ``Recipe`` checks how they fit together. Every field is a ``colorsort-baseline`` flag,
``--<section>.<field>=<value>`` (``flags``). The presets (``RECIPES``):

- ``state``: the simulator's box state (``observation.environment_state``) and the arm's; no cameras.
  The policy in ``baselines/act-state``.
- ``state-tracking``: the same on the never-stopping belt, whose state adds the belt encoder.
- ``camera``: the ``sensor`` and ``wrist`` cameras at 32 px and ``observation.state`` only. The policy in
  ``baselines/act-camera``.
- ``camera-snapshot``: the ``snapshot`` camera alone (the sensor's photo of the box taken when it reached the
  ray, held until the next). The policy in ``baselines/act-camera-snapshot``.
- ``camera-tracking``: the live ``sensor``, the ``snapshot`` and the ``wrist`` at 64 px on the never-stopping
  belt. The policy in ``baselines/act-camera-tracking``.
- ``camera-diffusion``: ``camera-snapshot``'s mix of demos, three times as many (144), at 64 px, learned by LeRobot's
  diffusion policy predicting the actions (not the noise), denoised in 10 DDIM steps, its weights stored in float16
  (a 25 MB file), its checkpoint chosen on 20 validation episodes of each training variant.
- ``camera-large``: the ``snapshot`` and ``wrist`` cameras at 128 px for LeRobot's ACT size, on a GPU.

Why each preset is what it is, with the measurements: docs/baselines.md.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any

from colorsort.data.perturbations import Perturbation
from colorsort.data.perturbations.brightness import Brightness
from colorsort.data.perturbations.late_pass import LatePass
from colorsort.data.perturbations.late_pick import LatePick
from colorsort.errors import ConfigError, UnknownName
from colorsort.shifts.registry import trainable, training_shifts
from colorsort.training.dagger_config import DaggerConfig
from colorsort.training.demos_config import DemosConfig, at_least_one
from colorsort.training.method_names import method_name
from colorsort.training.policy_config import LARGE_ACT, SMALL_ACT, SNAPSHOT_DIFFUSION, TRACKING_ACT, PolicyConfig
from colorsort.training.weights import WEIGHTS
from colorsort.variants import LIGHT_BRIGHTNESS, VALIDATION_SEEDS, VARIANTS, get_variant

# the ``lighting`` variant's warm-to-cold tints as colour temperatures [K] (its brightness: LIGHT_BRIGHTNESS)
RELIGHT_TEMPERATURE = (4500, 12000)
IRB140_VARIANTS = ("seed", "default", "fast", "jitter", "lighting", "distractors")
TRACKING_VARIANTS = ("tracking", "tracking-jitter", "tracking-fast")
CAMERA_MIX = (("default", 1.0), ("lighting", 1.0), ("jitter", 1.0), ("fast", 1.0), ("distractors", 2.0))
DEVICES = ("cpu", "cuda", "mps")
SECTIONS = ("demos", "policy", "training", "dagger", "evaluation")


@dataclass(frozen=True)
class TrainingConfig:
    """``lerobot-train``'s run: its length, seeds, batches, image augmentation and device."""

    # training updates of the largest demo set.
    steps: int = 6000
    # training updates of the smaller sets.
    small_steps: int = 2500
    # when set, every set trains for this many passes over its frames instead (updates = passes x frames / batch_size),
    # so that a demo curve compares sets trained alike.
    passes: float | None = None
    # ``lerobot-train`` seeds; every set is trained (and scored) once per seed. The first seed's policy is the one
    # shipped and the one whose checkpoints make the learning curve.
    seeds: tuple[int, ...] = (1000,)
    # samples per update.
    batch_size: int = 64
    # updates between checkpoints (the learning curve's points); 0: the last only.
    save_every: int = 0
    # random shifts of every training image (LeRobot's ``RandomAffine``), up to this fraction of its width and height
    # each way; 0: off.
    image_shift: float = 0.0
    # every training image relit at random as the ``lighting`` variant relights the cell (brightness, ``ColorJitter``;
    # colour temperature 4,500-12,000 K, ``PlanckianJitter``).
    image_relight: bool = False
    # ``lerobot-train``'s device: cpu, cuda or mps.
    device: str = "cpu"
    # ``lerobot-train``'s data-loading processes. LeRobot spawns each (each imports torch and LeRobot again before the
    # first batch); 0 loads in the training process. The random draws of the image augmentation depend on it, so it is
    # part of a run's cache key.
    num_workers: int = 1
    # how the checkpoints store their weights: float32 as ``lerobot-train`` writes them, or float16 (half the file;
    # rounded before any checkpoint is validated or scored, so every score is of the stored weights:
    # ``colorsort.training.weights``).
    weights: str = "float32"
    # checkpoints in each scored one: 1, ``lerobot-train``'s weights; k > 1, each checkpoint's weights the mean of its
    # own and the k - 1 saved before it (every ``save_every`` updates), as Diffusion Policy scores a moving average of
    # its weights (``colorsort.training.weights.average``).
    average: int = 1

    def __post_init__(self) -> None:
        at_least_one(self, "steps", "small_steps", "batch_size", "average")
        if self.average > 1 and not self.save_every:
            raise ConfigError(f"average={self.average} averages checkpoints saved along the run: give save_every "
                              "above 0 too (or average=1)")
        if self.weights not in WEIGHTS:
            raise ConfigError(f"weights={self.weights!r}: valid weights are {list(WEIGHTS)}")
        if self.num_workers < 0:
            raise ConfigError(f"num_workers={self.num_workers}: give 0 (load in the training process) or more")
        if self.passes is not None and not self.passes > 0:
            raise ConfigError(f"passes={self.passes}: give a number above 0, or None for fixed updates")
        if not self.seeds or len(set(self.seeds)) != len(self.seeds) or min(self.seeds) < 0:
            raise ConfigError(f"seeds={self.seeds}: give one or more distinct seeds, each 0 or more")
        if self.save_every < 0:
            raise ConfigError(f"save_every={self.save_every}: give 0 (last checkpoint only) or more")
        if not 0 <= self.image_shift < 0.5:
            raise ConfigError(f"image_shift={self.image_shift}: give 0 (off) up to 0.5 (a fraction of the image)")
        if self.device not in DEVICES:
            raise ConfigError(f"device={self.device!r}: valid devices are {list(DEVICES)}")

    def updates(self, largest: bool, frames: int) -> int:
        """Training updates for a set of ``frames`` frames, the largest set or a smaller one."""
        if self.passes is not None:
            return max(1, round(self.passes * frames / self.batch_size))
        return self.steps if largest else self.small_steps

    def augment_args(self) -> list[str]:
        """``lerobot-train``'s arguments for the image transforms: every one asked for, applied to every image."""
        tfs: dict[str, dict] = {}
        if self.image_shift:
            tfs["shift"] = {"weight": 1.0, "type": "RandomAffine",
                            "kwargs": {"degrees": 0, "translate": [self.image_shift, self.image_shift]}}
        if self.image_relight:
            tfs["brightness"] = {"weight": 1.0, "type": "ColorJitter",
                                 "kwargs": {"brightness": list(LIGHT_BRIGHTNESS)}}
            tfs["temperature"] = {"weight": 1.0, "type": "PlanckianJitter",
                                  "kwargs": {"temperature": list(RELIGHT_TEMPERATURE)}}
        if not tfs:
            return []
        return ["--dataset.image_transforms.enable=true", f"--dataset.image_transforms.max_num_transforms={len(tfs)}",
                f"--dataset.image_transforms.tfs={json.dumps(tfs)}"]


@dataclass(frozen=True)
class EvaluationConfig:
    """How the trained policies are scored (``colorsort-eval`` on each variant's fixed evaluation seeds)."""

    # the variant of the headline score, the demo curve and the learning curve.
    main_variant: str = "default"
    # the variants the largest set's policy is scored on.
    variants: tuple[str, ...] = IRB140_VARIANTS
    # evaluation episodes on ``main_variant``.
    episodes: int = 50
    # evaluation episodes on every other variant.
    other_episodes: int = 20
    # episodes per learning-curve checkpoint (the main variant's first seeds).
    curve_episodes: int = 20
    # when above 0, every checkpoint plays this many episodes of each training variant on validation seeds (never the
    # evaluation seeds), and the one that does best there is scored and shipped (``colorsort.training.selection``); 0:
    # the last checkpoint.
    select_episodes: int = 0
    # held-out shifts' training ranges the checkpoints also play their validation episodes under (as
    # ``DemosConfig.shift``; "": unshifted only), so that the one chosen holds under the ranges it trained on too.
    select_shift: str = ""
    # evaluation steps before truncation (None: the variant's time limit).
    episode_length: int | None = None

    def __post_init__(self) -> None:
        for name in (*self.variants, self.main_variant):
            get_variant(name)
        if self.main_variant not in self.variants:
            raise ConfigError(f"main_variant={self.main_variant!r} must be one of variants {self.variants}")
        at_least_one(self, "episodes", "other_episodes", "curve_episodes")
        training_shifts(self.select_shift, "evaluation.select_shift")  # ConfigError naming a held-out level
        if not 0 <= self.select_episodes <= len(VALIDATION_SEEDS):
            raise ConfigError(f"select_episodes={self.select_episodes}: give 0 (the last checkpoint) up to "
                              f"{len(VALIDATION_SEEDS)} (the validation seeds)")
        if self.episode_length is not None and self.episode_length < 1:
            raise ConfigError(f"episode_length={self.episode_length}: give at least 1, or None")

    def episodes_on(self, variant: str) -> int:
        return self.episodes if variant == self.main_variant else self.other_episodes


@dataclass(frozen=True)
class Recipe:
    """One learned baseline, from demos to scores: its preset's ``name`` and five sections."""

    name: str
    demos: DemosConfig = field(default_factory=DemosConfig)
    policy: PolicyConfig = SMALL_ACT
    training: TrainingConfig = field(default_factory=TrainingConfig)
    evaluation: EvaluationConfig = field(default_factory=EvaluationConfig)
    dagger: DaggerConfig = field(default_factory=DaggerConfig)

    def __post_init__(self) -> None:
        self._check_fit()
        if (self.training.image_shift or self.training.image_relight) and not self.demos.cameras:
            raise ConfigError("training.image_shift and training.image_relight change camera images: give "
                              "demos.cameras, or turn them off")
        unknown = [v for v in self.dagger.variants if v not in self.demos.train_variants]
        if unknown:
            raise ConfigError(f"dagger.variants {unknown}: give training variants of this recipe, "
                              f"{list(self.demos.train_variants)} (or none: all of them)")
        if self.dagger.rollout == "chosen" and not self.evaluation.select_episodes:
            raise ConfigError("dagger.rollout='chosen' plays the checkpoint validation seeds choose, and "
                              "evaluation.select_episodes=0 chooses none: give select_episodes, or rollout='last'")
        if self.evaluation.select_episodes and not self.training.save_every:
            raise ConfigError(f"evaluation.select_episodes={self.evaluation.select_episodes} chooses among "
                              "checkpoints, and training.save_every=0 saves only the last: give save_every, or "
                              "select_episodes=0")

    def _check_fit(self) -> None:
        """ConfigError when the policy trained on ``train_mix`` could not run on an evaluation variant."""
        def shape(name: str) -> tuple[str, bool]:  # what sets the sizes of the state and the action
            v = get_variant(name)
            return v.robot, v.task_config.tracking

        trained = {shape(v) for v in self.demos.train_variants}
        if len(trained) > 1:
            raise ConfigError(f"train_mix {list(self.demos.train_variants)} mixes robots or belts (state sizes "
                              "differ): train on variants of one robot and one belt")
        (wanted,) = trained
        bad = [v for v in self.evaluation.variants if shape(v) != wanted]
        if bad:
            fits = [v for v in VARIANTS if shape(v) == wanted]
            raise ConfigError(f"evaluation variants {bad} do not fit a policy trained on "
                              f"{list(self.demos.train_variants)} (state sizes differ); variants it fits: {fits}")

    @property
    def label(self) -> str:
        method = method_name(self.policy.type, self.dagger.rounds, self.dagger.retrain, self.training.average)
        randomised = ", randomised shifts" if self.demos.shift else ""
        return f"{method}, {'+'.join(self.demos.cameras) if self.demos.cameras else 'state'}{randomised}"

    def override(self, changes: dict[str, Any]) -> Recipe:
        """This recipe with ``changes`` made, keyed ``section.field`` (``{"demos.counts": (8,)}``); a perturbation
        by its name (``{"demos.late_pick": LatePick(10)}``); ConfigError naming the valid keys otherwise."""
        sections: dict[str, dict[str, Any]] = {s: {} for s in SECTIONS}
        valid = {f"{s}.{f.name}" for s in SECTIONS for f in fields(getattr(self, s)) if f.init}
        perturbations = {p.name: p for p in self.demos.perturbations}
        for key, value in changes.items():
            section, _, name = key.partition(".")
            if isinstance(value, Perturbation) and section == "demos":
                perturbations[value.name] = value
                sections["demos"]["perturbations"] = tuple(perturbations.values())
            elif key in valid:
                sections[section][name] = value
            else:
                raise UnknownName("recipe setting", key, sorted(valid), "settings")
        new = {s: replace(getattr(self, s), **c) for s, c in sections.items() if c}
        return replace(self, **new)

    def to_json(self) -> dict:
        """The recipe as JSON, stored with its results: every section's fields, the policy's type, and the
        perturbations by name."""
        demos = {f.name: getattr(self.demos, f.name) for f in fields(self.demos) if f.name != "perturbations"}
        demos["perturbations"] = {p.name: p.settings() for p in self.demos.perturbations}
        if not self.demos.shift:  # a recipe without shifts reads as before they were a setting
            del demos["shift"]
        sections = {"name": self.name, "demos": demos, "policy": {**asdict(self.policy), "type": self.policy.type},
                    "training": asdict(self.training), "evaluation": asdict(self.evaluation)}
        if self.dagger.rounds:  # a recipe without rounds reads as before DAgger was a setting
            sections["dagger"] = asdict(self.dagger)
        return json.loads(json.dumps(sections))

# Every training range but box-size's: the expert descends to a 10 cm top, so it sorts a third of the episodes
# with a box up to 1 cm smaller (docs/shifts.md), and a demo it fails is not kept.
DR_SHIFTS = ",".join(f"{name}:train" for name in ("camera-pose", "robot-start", "box-shade", "belt-look", "backdrop",
                                                    "light-color", "image-noise", "box-mass", "belt-speed",
                                                    "joint-noise", "box-offset"))

# Every shift with a training range, box-size's too now that the expert touches off whatever a box's height
# (box-shape and novel-distractors have none: wholly unseen; action-delay and image-blur have none either).
TOUCH_DR_SHIFTS = ",".join(f"{name}:train" for name in trainable())
# The randomised recipe's policies, on demos of the touch-off expert: every training range, twice the demos, the
# checkpoint chosen under the ranges too. A box waiting at a still arm must be labelled go about as often as pass:
# with late_pass 100 and late_pick 10 (2,274 frames pass, 1,234 go) a seed let every red box through, with late_pass
# 30 and late_pick 10 (980 against 1,243) it let no distractor through; with late_pass 100 and late_pick 30 (2,273
# against 3,223) seed 1001 sorts both, seed 1000 still lets no distractor through: the balance alone does not settle
# the decision (docs/studies/2026-12-touch-dr-first-seed.md). The images are not relit: the Planckian jitter was not
# the cause there, and the demos' light-color and lighting ranges relight the cell itself.
TOUCH_DR_DEMOS = DemosConfig(train_mix=CAMERA_MIX, counts=(96,), cameras=("snapshot",), image_size=32,
                             perturbations=(LatePass(100), LatePick(30), Brightness(0.45, 0.75)), shift=TOUCH_DR_SHIFTS)
TOUCH_DR_EVALUATION = EvaluationConfig(select_episodes=10, select_shift=TOUCH_DR_SHIFTS)

RECIPES: dict[str, Recipe] = {r.name: r for r in (
    Recipe("state",
           DemosConfig(train_mix=(("default", 1), ("jitter", 1), ("fast", 1), ("distractors", 2)), counts=(40,),
                        perturbations=(LatePass(100),)),
           training=TrainingConfig(steps=10000, save_every=2500, seeds=(1000, 1001, 1002))),
    Recipe("state-tracking",
           DemosConfig(train_mix=(("tracking", 1), ("tracking-jitter", 1)), counts=(40,), boxes_per_episode=5),
           TRACKING_ACT, TrainingConfig(steps=3000),
           EvaluationConfig(main_variant="tracking", variants=TRACKING_VARIANTS)),
    Recipe("camera",
           DemosConfig(train_mix=CAMERA_MIX, counts=(48,), cameras=("sensor", "wrist"), image_size=32,
                        perturbations=(LatePass(100),)),
           training=TrainingConfig(steps=8000, save_every=2000, seeds=(1000, 1001, 1002), batch_size=32,
                                  image_shift=0.1)),
    Recipe("camera-snapshot",
           DemosConfig(train_mix=CAMERA_MIX, counts=(48,), cameras=("snapshot",), image_size=32,
                        perturbations=(LatePass(100), LatePick(10), Brightness(0.45, 0.75))),
           replace(SMALL_ACT, optimizer_lr=3e-4, optimizer_lr_backbone=3e-4),
           TrainingConfig(steps=4000, save_every=1000, seeds=(1001, 1000, 1002), batch_size=32, image_shift=0.1),
           EvaluationConfig(select_episodes=10)),
    Recipe("camera-snapshot-dr",  # camera-snapshot's demos and training, the demos recorded with DR_SHIFTS
           DemosConfig(train_mix=CAMERA_MIX, counts=(48,), cameras=("snapshot",), image_size=32,
                        perturbations=(LatePass(100), LatePick(10), Brightness(0.45, 0.75)), shift=DR_SHIFTS),
           replace(SMALL_ACT, optimizer_lr=3e-4, optimizer_lr_backbone=3e-4),
           TrainingConfig(steps=4000, save_every=1000, seeds=(1001, 1000, 1002), batch_size=32, image_shift=0.1,
                         weights="float16"),
           EvaluationConfig(select_episodes=10)),
    Recipe("camera-snapshot-touch-dr", TOUCH_DR_DEMOS,
           replace(SMALL_ACT, optimizer_lr=3e-4, optimizer_lr_backbone=3e-4),
           TrainingConfig(steps=4000, save_every=1000, seeds=(1001, 1000, 1002), batch_size=32, image_shift=0.1,
                          weights="float16"),
           TOUCH_DR_EVALUATION),
    Recipe("camera-diffusion-touch-dr", TOUCH_DR_DEMOS, SNAPSHOT_DIFFUSION,
           TrainingConfig(steps=4000, save_every=1000, seeds=(1001, 1000, 1002), batch_size=32, weights="float16"),
           TOUCH_DR_EVALUATION),
    Recipe("camera-tracking",
           DemosConfig(train_mix=(("tracking", 1), ("tracking-jitter", 1)), counts=(48,), boxes_per_episode=5,
                        cameras=("sensor", "snapshot", "wrist"), image_size=64),
           TRACKING_ACT, TrainingConfig(steps=3600, save_every=1200, seeds=(1001, 1000, 1002), batch_size=32),
           EvaluationConfig(main_variant="tracking", variants=TRACKING_VARIANTS, select_episodes=10)),
    Recipe("camera-diffusion",
           DemosConfig(train_mix=CAMERA_MIX, counts=(144,), cameras=("snapshot",), image_size=64,
                        perturbations=(LatePass(100), LatePick(10), Brightness(0.45, 0.75))),
           SNAPSHOT_DIFFUSION, TrainingConfig(steps=4000, save_every=2000, seeds=(1001, 1000, 1002), batch_size=32,
                                             weights="float16"),
           EvaluationConfig(select_episodes=20)),
    Recipe("camera-large",
           DemosConfig(train_mix=CAMERA_MIX, counts=(48,), cameras=("snapshot", "wrist"), image_size=128,
                        perturbations=(LatePass(100),)),
           LARGE_ACT, TrainingConfig(steps=6000, save_every=1000, batch_size=32, image_shift=0.1, device="cuda")),
)}


def get_recipe(name: str, changes: dict[str, Any] | None = None) -> Recipe:
    """The preset ``name`` with ``changes`` (``Recipe.override``); ConfigError naming the valid presets otherwise."""
    if name not in RECIPES:
        raise UnknownName("recipe", name, list(RECIPES), "recipes")
    return RECIPES[name].override(changes or {})
