"""The LeRobot policies a recipe trains: ACT and diffusion, each as ``lerobot-train``'s ``--policy.*`` arguments.

Both kinds answer the same questions, so the pipeline never asks which one it holds:

- ``type``: ``lerobot-train --policy.type`` (its name in tables: ``colorsort.training.method_names``);
- ``args(image_size)``: the ``--policy.<name>=<value>`` arguments (and any optimizer ones);
- ``inference()``: the settings that change how a trained policy acts but not what it learns;
- ``execution``: how its action chunks are executed, for file names (``chunk10``, ``ens0.01``);
- ``describe(parameters)``: one sentence for a shipped policy's README.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import draccus

from colorsort.errors import ConfigError

LR_SCHEDULES = ("constant", "cosine")
NOISE_SCHEDULERS = ("DDPM", "DDIM")  # diffusers' schedulers LeRobot's diffusion policy builds
PREDICTION_TYPES = ("epsilon", "sample")  # what the U-Net predicts: the noise added, or the clean actions
DEFAULT_LR = 1e-4  # ACT's learning rate here, its backbone's too


def _text(value: object) -> str:
    """A value as ``lerobot-train``'s command line spells it (``true``, ``null``, ``[32,64]``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "null"
    if isinstance(value, (tuple, list)):
        return "[" + ",".join(map(str, value)) + "]"
    return str(value)


@dataclass(frozen=True)
class PolicyConfig(draccus.ChoiceRegistry):
    """A policy a recipe trains; ``--policy.type`` picks the kind (``act``, ``diffusion``), as on ``lerobot-train``."""

    @property
    def type(self) -> str:
        """``lerobot-train --policy.type``."""
        return str(self.get_choice_name(type(self)))

    @property
    def execution(self) -> str:
        """How its action chunks are executed, for file names."""
        raise NotImplementedError

    def inference(self) -> dict[str, float | int | str | None]:
        """The settings that change how a trained policy acts but not what it learns."""
        raise NotImplementedError

    def args(self, image_size: int) -> list[str]:
        """``lerobot-train``'s ``--policy.*`` arguments (and any optimizer ones) for images of ``image_size`` px."""
        raise NotImplementedError

    def describe(self, parameters: int) -> str:
        """One sentence of a shipped policy's README: its size and how it acts."""
        raise NotImplementedError


@PolicyConfig.register_subclass("act")
@dataclass(frozen=True)
class ActConfig(PolicyConfig):
    """LeRobot ACT settings, passed to ``lerobot-train`` as ``--policy.<name>=<value>``."""

    dim_model: int = 128  # the transformer's width (LeRobot's 512)
    dim_feedforward: int = 512  # its feed-forward layers' width (LeRobot's 3200)
    n_heads: int = 4  # attention heads (LeRobot's 8)
    n_encoder_layers: int = 2  # transformer encoder layers (LeRobot's 4)
    n_decoder_layers: int = 1  # transformer decoder layers (LeRobot's 1)
    chunk_size: int = 20  # actions predicted per inference [steps of 50 ms]
    n_action_steps: int = 10  # actions executed open-loop per inference (1 with temporal ensembling)
    temporal_ensemble_coeff: float | None = None  # set: ACT's temporal ensembling (see TRACKING_ACT)
    use_vae: bool = False  # the expert is deterministic: one mode per state, nothing for a latent to explain
    optimizer_lr: float = DEFAULT_LR  # LeRobot's 1e-5 is tuned for a pretrained backbone; these start from scratch
    optimizer_lr_backbone: float = DEFAULT_LR  # the ResNet-18's learning rate
    pretrained_backbone_weights: str | None = None  # ImageNet weights would be a download: none at run time
    lr_schedule: str = "constant"  # LeRobot's ACT preset; "cosine": warm up, then anneal to 0 at the last update
    warmup_steps: int = 200  # updates of linear warm-up before the cosine [updates]

    def __post_init__(self) -> None:
        if self.lr_schedule not in LR_SCHEDULES:
            raise ConfigError(f"lr_schedule={self.lr_schedule!r}: valid schedules are {list(LR_SCHEDULES)}")
        if self.warmup_steps < 0:
            raise ConfigError(f"warmup_steps={self.warmup_steps}: give 0 or more")
        if not 1 <= self.n_action_steps <= self.chunk_size:
            raise ConfigError(f"n_action_steps={self.n_action_steps}: give 1 to chunk_size ({self.chunk_size})")
        if self.temporal_ensemble_coeff is not None and self.n_action_steps != 1:
            raise ConfigError(f"temporal_ensemble_coeff={self.temporal_ensemble_coeff} needs n_action_steps=1 "
                             f"(got {self.n_action_steps}); or set temporal_ensemble_coeff=None")

    @property
    def execution(self) -> str:
        """How the chunks are executed, for file names: ``ens0.01`` or ``chunk10``."""
        if self.temporal_ensemble_coeff is not None:
            return f"ens{self.temporal_ensemble_coeff:g}"
        return f"chunk{self.n_action_steps}"

    def inference(self) -> dict[str, float | int | str | None]:
        """The settings that change how a trained ACT acts but not what it learns."""
        return {"n_action_steps": self.n_action_steps, "temporal_ensemble_coeff": self.temporal_ensemble_coeff}

    def args(self, image_size: int) -> list[str]:
        """``lerobot-train``'s arguments for the policy, its optimizer and its learning-rate schedule.

        ``image_size`` [px] is unused: ACT reads its images whole."""
        policy = {k: v for k, v in asdict(self).items() if k not in ("lr_schedule", "warmup_steps")}
        args = [f"--policy.{k}={_text(v)}" for k, v in policy.items()]
        if self.lr_schedule == "cosine":
            if self.optimizer_lr_backbone != self.optimizer_lr:
                raise ConfigError("lr_schedule='cosine' trains every parameter at optimizer_lr: "
                                 f"give optimizer_lr_backbone={self.optimizer_lr} too")
            # LeRobot's ACT preset has no schedule, so the optimizer is spelt out (ACT's own AdamW settings)
            args += ["--use_policy_training_preset=false", "--optimizer.type=adamw",
                     f"--optimizer.lr={self.optimizer_lr}", "--optimizer.weight_decay=0.0001",
                     "--optimizer.grad_clip_norm=10", "--scheduler.type=cosine_annealing_with_warmup",
                     f"--scheduler.num_warmup_steps={self.warmup_steps}"]
        return args

    def describe(self, parameters: int) -> str:
        """One sentence of a shipped policy's README: its size and how it acts."""
        execution = (f"predicted every step and averaged over the chunks (temporal ensembling, coefficient "
                     f"{self.temporal_ensemble_coeff})" if self.temporal_ensemble_coeff is not None
                     else f"of which {self.n_action_steps} are executed")
        return (f"LeRobot ACT ({parameters / 1e6:.2f} M parameters, {self.dim_model}-dim, {self.n_encoder_layers} "
                f"encoder and {self.n_decoder_layers} decoder layers, chunks of {self.chunk_size} actions "
                f"{execution}, {'a' if self.use_vae else 'no'} VAE, learning rate {self.optimizer_lr})")


@PolicyConfig.register_subclass("diffusion")
@dataclass(frozen=True)
class DiffusionConfig(PolicyConfig):
    """LeRobot diffusion policy settings for small images trained from scratch on a CPU.

    Its image encoder is what ACT's is not: a ResNet-18 whose batch norms become GroupNorm (a working
    normalisation with no pretrained statistics; ACT's are frozen), ending in a spatial softmax that
    gives the image coordinates of ``spatial_softmax_num_keypoints`` learned keypoints (where things
    are, not only what), after a random crop (training) or the centre crop (inference) of
    ``crop_fraction`` of each image side. One encoder serves every camera (the shipped file stays
    under 50 MB).
    """

    n_obs_steps: int = 1  # observations per prediction: 2 costs 1.0 s an update here against 0.69
    horizon: int = 16  # actions predicted per inference [steps of 50 ms]
    n_action_steps: int = 8  # actions executed open-loop per inference
    down_dims: tuple[int, ...] = (32, 64)  # the U-Net's channels per level (LeRobot's 512, 1024, 2048: 250 M)
    use_group_norm: bool = True  # GroupNorm in place of the ResNet's batch norms (no pretrained statistics)
    spatial_softmax_num_keypoints: int = 32  # image keypoints the encoder ends in
    use_separate_rgb_encoder_per_camera: bool = False  # one encoder serves every camera (the file stays small)
    pretrained_backbone_weights: str | None = None  # ImageNet weights would be a download: none at run time
    num_inference_steps: int = 10  # denoising steps per inference (of num_train_timesteps in training)
    noise_scheduler_type: str = "DDPM"  # DDIM: deterministic denoising in few steps; the same training either way
    num_train_timesteps: int = 100  # the forward diffusion's steps
    prediction_type: str = "epsilon"  # "sample": the U-Net predicts the clean actions instead of the noise
    optimizer_lr: float = DEFAULT_LR  # Adam's rate at the end of the warm-up, then annealed (cosine) to 0
    scheduler_warmup_steps: int = 500  # updates of linear warm-up [updates]
    crop_fraction: float = 0.9  # the crop's side as a fraction of the image's

    def __post_init__(self) -> None:
        if not 1 <= self.n_action_steps <= self.horizon - self.n_obs_steps + 1:
            raise ConfigError(f"n_action_steps={self.n_action_steps}: give 1 to horizon - n_obs_steps + 1 "
                             f"({self.horizon - self.n_obs_steps + 1})")
        if self.n_obs_steps < 1 or self.num_inference_steps < 1:
            raise ConfigError(f"n_obs_steps={self.n_obs_steps}, num_inference_steps={self.num_inference_steps}: "
                             "give at least 1 each")
        if not self.down_dims or self.horizon % 2 ** len(self.down_dims):
            raise ConfigError(f"horizon={self.horizon}: give a multiple of 2 ** len(down_dims) "
                             f"({2 ** len(self.down_dims)}), with at least one level in down_dims")
        if not 0.5 <= self.crop_fraction <= 1:
            raise ConfigError(f"crop_fraction={self.crop_fraction}: give 0.5 to 1 (1: no crop)")
        if self.noise_scheduler_type not in NOISE_SCHEDULERS:
            raise ConfigError(f"noise_scheduler_type={self.noise_scheduler_type!r}: valid schedulers are "
                             f"{list(NOISE_SCHEDULERS)}")
        if self.prediction_type not in PREDICTION_TYPES:
            raise ConfigError(f"prediction_type={self.prediction_type!r}: valid types are {list(PREDICTION_TYPES)}")
        if not 1 <= self.num_inference_steps <= self.num_train_timesteps:
            raise ConfigError(f"num_inference_steps={self.num_inference_steps}: give 1 to num_train_timesteps "
                             f"({self.num_train_timesteps})")
        if self.optimizer_lr <= 0 or self.scheduler_warmup_steps < 0:
            raise ConfigError(f"optimizer_lr={self.optimizer_lr}, scheduler_warmup_steps="
                             f"{self.scheduler_warmup_steps}: give a positive rate and 0 or more updates")

    @property
    def execution(self) -> str:
        """How the predictions are executed, for file names: ``chunk8-ddpm10`` (actions executed, the scheduler and
        its denoising steps: every inference setting, so that an evaluation under others is never reused)."""
        return f"chunk{self.n_action_steps}-{self.noise_scheduler_type.lower()}{self.num_inference_steps}"

    def inference(self) -> dict[str, float | int | str | None]:
        """The settings that change how a trained diffusion policy acts but not what it learns (DDIM and DDPM
        add noise alike in training, and differ only in how they take it away)."""
        return {"n_action_steps": self.n_action_steps, "num_inference_steps": self.num_inference_steps,
                "noise_scheduler_type": self.noise_scheduler_type}

    def crop(self, image_size: int) -> int:
        """The crop's side [px] for square images of ``image_size`` px."""
        return round(self.crop_fraction * image_size)

    def args(self, image_size: int) -> list[str]:
        """``lerobot-train``'s arguments; LeRobot's own optimizer and schedule (Adam, cosine after a warm-up) at the
        settings' rate and warm-up."""
        policy = {k: v for k, v in asdict(self).items() if k not in ("crop_fraction",)}
        args = [f"--policy.{k}={_text(v)}" for k, v in policy.items()]
        if self.crop_fraction < 1:
            args.append(f"--policy.crop_shape={_text([self.crop(image_size)] * 2)}")
        return args

    def describe(self, parameters: int) -> str:
        """One sentence of a shipped policy's README: its size and how it acts."""
        predicts = "noise" if self.prediction_type == "epsilon" else "actions"
        return (f"LeRobot diffusion policy ({parameters / 1e6:.2f} M parameters, a U-Net of "
                f"{', '.join(map(str, self.down_dims))} channels over {self.horizon} actions of which "
                f"{self.n_action_steps} are executed, predicting the {predicts} over {self.num_train_timesteps} "
                f"diffusion steps, {self.num_inference_steps} {self.noise_scheduler_type} denoising steps, "
                f"learning rate {self.optimizer_lr}, "
                f"{self.n_obs_steps} observation{'s' if self.n_obs_steps > 1 else ''} per prediction, "
                f"ResNet-18 with GroupNorm and a spatial softmax of {self.spatial_softmax_num_keypoints} "
                f"keypoints, random crops of {self.crop_fraction:g} of each side)")


SMALL_ACT = ActConfig()  # 0.67 M parameters without cameras; 11.9 M with the ResNet-18
# the belt that never stops: each step's action the average of every chunk's prediction for it, the k-th weighted
# exp(-0.2 k) so that the plan made first counts most (why 0.2: docs/baselines.md, "How ACT acts")
TRACKING_ACT = ActConfig(n_action_steps=1, temporal_ensemble_coeff=0.2)
LARGE_ACT = ActConfig(dim_model=512, dim_feedforward=3200, n_heads=8, n_encoder_layers=4)  # LeRobot's own size
# what learned within the hour here (one 64 px camera): the U-Net predicts the clean actions, which it learns as a
# regression first, where the noise it predicted before had not been learned after 4,500 updates; DDIM takes that
# noise away in 10 deterministic steps; 3e-4, as ACT; and two levels of 64 and 128 channels (a 1.37 M U-Net, 12.56 M
# in all), where 32 and 64 sorted 32% of `default` and 64, 128, 256 52% (docs/baselines.md, "Other LeRobot policies:
# diffusion")
SNAPSHOT_DIFFUSION = DiffusionConfig(down_dims=(64, 128), prediction_type="sample", noise_scheduler_type="DDIM",
                                       optimizer_lr=3e-4, scheduler_warmup_steps=200)
