"""DAgger's labels (Ross et al., 2011): a learned policy drives the cell, the expert takes over from the state it
reached and finishes the episode, and the expert's frames from that state on are recorded as a LeRobot dataset.

Each episode: the policy acts for a number of steps drawn from the episode's seed (``handover``), as in an
evaluation (the same gym env, the cameras and image size its checkpoint was trained on); then
``Expert.take_over`` plans from wherever the arm, the cup and the boxes are, and every frame from that state to the
episode's end is stored with the expert's action as its label. An episode the expert finishes with every box in
the bin of its colour is kept. The frames carry their own task text (``TAKEOVER_TASK``) and the dataset a
``meta/takeover.json`` of where they came from, so they are told apart from demos after a merge; the features are
the demos' (``schema.features``), so LeRobot's ``aggregate_datasets`` merges the two.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from colorsort.benchmark.evaluate import observation_settings
from colorsort.benchmark.policies import LeRobotPolicy
from colorsort.cell.privileged import take_over_view
from colorsort.data.config import CollectConfig, check_vcodec
from colorsort.envs.gym_env import ColorSortGymEnv
from colorsort.envs.rollout import GymEpisode, Observer, Step, rollout
from colorsort.envs.schema import features, frame
from colorsort.errors import ConfigError
from colorsort.expert.config import ExpertConfig, changes_text, recording_expert
from colorsort.expert.factory import make_expert
from colorsort.variants import get_variant

TAKEOVER_SEED = 40_000  # first episode seed: apart from the demos' (0), evaluation (10,000) and validation (20,000)
TAKEOVER_TASK = "Finish sorting from the state a learned policy left: the expert's labels (DAgger)."
PROVENANCE = "takeover.json"  # under meta/: the policy, variant, seeds and handover steps of the episodes


@dataclass(frozen=True)
class TakeoverConfig:
    """What to record.

    Attributes:
        policy: a LeRobot checkpoint (``pretrained_model`` folder) that drives the first steps.
        out: a new dataset folder (an existing one is refused).
        variant: the benchmark variant whose episodes are played.
        episodes: episodes to play; episode i has env seed ``seed + i``.
        handover: [steps] the policy acts for a number of steps drawn uniformly from this range (inclusive), from
            a generator seeded by the episode's seed, before the expert takes over.
        seed: the first episode's env seed.
        repo_id: the dataset's LeRobot repo id.
        vcodec: the camera streams' video codec (``colorsort-collect``'s ``--vcodec``): LeRobot merges the labels
            with demos only when their features, codec included, are the same.
        expert: the expert's settings changed from its belt's preset, (name, value) pairs
            (``colorsort-collect``'s ``--expert``): the labels come from the expert that made the demos.
        turn_to_box: the expert turns the cup to a turned box; False keeps its home yaw (``colorsort-collect``'s
            ``--no-turn``), as the demos' expert did.
    """

    policy: str
    out: str
    variant: str = "default"
    episodes: int = 10
    handover: tuple[int, int] = (20, 200)
    seed: int = TAKEOVER_SEED
    repo_id: str = "local/colorsort-takeover"
    vcodec: str = CollectConfig.vcodec
    expert: tuple[tuple[str, float], ...] = ()
    turn_to_box: bool = True

    def __post_init__(self) -> None:
        get_variant(self.variant)  # ConfigError naming the valid variants
        self.expert_config  # noqa: B018 - validates the expert's changes
        check_vcodec(self.vcodec)
        if self.episodes < 1:
            raise ConfigError(f"episodes={self.episodes}: give at least 1")
        lo, hi = self.handover
        if not 0 <= lo <= hi:
            raise ConfigError(f"handover={self.handover}: give (first, last) steps with 0 <= first <= last")
        if self.seed < 0:
            raise ConfigError(f"seed={self.seed}: give 0 or more")

    def settings(self) -> dict[str, Any]:
        """What the labels depend on beside the policy: the key of the pipeline's cache of them (not ``out``)."""
        return {"variant": self.variant, "episodes": self.episodes, "handover": list(self.handover), "seed": self.seed,
                "repo_id": self.repo_id, "vcodec": self.vcodec, "expert": [list(c) for c in self.expert],
                "turn_to_box": self.turn_to_box}

    def argv(self) -> list[str]:
        """``colorsort-takeover``'s flags that parse back into this configuration."""
        return (["--policy", self.policy, "--out", self.out, "--variant", self.variant, "--episodes",
                 str(self.episodes), "--handover", "{},{}".format(*self.handover), "--seed", str(self.seed),
                 "--repo-id", self.repo_id, "--vcodec", self.vcodec]
                + ([f"--expert={changes_text(self.expert)}"] if self.expert else [])
                + ([] if self.turn_to_box else ["--no-turn"]))

    @property
    def expert_config(self) -> ExpertConfig:
        """The expert that takes over: its belt's preset, ``turn_to_box`` and the ``expert`` changes."""
        return recording_expert(get_variant(self.variant).task_config.tracking, self.turn_to_box, self.expert)


@dataclass
class TakeoverSummary:
    """What was played and kept."""

    root: str
    kept: list[int] = field(default_factory=list)  # env seeds whose episodes were saved
    failed: dict[int, str] = field(default_factory=dict)  # env seed -> why not kept
    handed_over_at: dict[int, int] = field(default_factory=dict)  # env seed -> policy steps before the take-over
    frames: int = 0  # frames saved


def handover_step(seed: int, handover: tuple[int, int]) -> int:
    """The policy's steps in the episode of env seed ``seed``: drawn from its own generator, so the same seed gives
    the same handover whatever else was recorded."""
    return int(np.random.default_rng([seed, 0x7A6E]).integers(handover[0], handover[1] + 1))


class Labels(Observer):
    """DAgger's labels: each frame from the handover on, the robosuite observation acted on and the expert's
    action, with the take-overs' own task text."""

    def __init__(self, gym: ColorSortGymEnv, dataset: Any, cameras: tuple[str, ...]):
        self.gym, self.dataset, self.cameras = gym, dataset, cameras

    def on_action(self, obs: Any, step: Step) -> None:
        self.dataset.add_frame(frame(self.gym.env, self.gym.raw_obs, step.stored, self.cameras, TAKEOVER_TASK))


def record_takeovers(config: TakeoverConfig) -> TakeoverSummary:
    """Play ``config.episodes`` episodes, the policy first and the expert from the handover on; save every episode
    the expert finished right as a LeRobot episode of its frames. The dataset is finalized whatever stops it."""
    from lerobot.configs.video import RGBEncoderConfig
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    root = Path(config.out)
    if root.exists():
        raise ConfigError(f"{root} exists: give a new folder (a recorded dataset is never overwritten)")
    cameras, image_size = observation_settings(config.policy, None, None)  # as the checkpoint was trained
    policy = LeRobotPolicy(config.policy)
    # render_mode keeps an off-screen renderer for the expert's sensor camera even where the policy reads none
    gym = ColorSortGymEnv(config.variant, cameras=cameras, image_size=image_size, render_mode="rgb_array")
    summary = TakeoverSummary(str(root))
    seeds = [config.seed + i for i in range(config.episodes)]
    dataset = LeRobotDataset.create(config.repo_id, gym.fps, features(gym.env, cameras, image_size), root=root,
                                    robot_type=gym.variant.robot, use_videos=True, video_backend="pyav",
                                    rgb_encoder=RGBEncoderConfig(vcodec=config.vcodec))
    expert = make_expert(gym.env, config.expert_config)
    try:
        for seed in seeds:
            obs, _ = gym.reset(seed=seed)
            policy.reset(gym, seed)
            steps = summary.handed_over_at[seed] = handover_step(seed, config.handover)
            episode = GymEpisode(gym)
            if rollout(episode, obs, policy.act, max_steps=steps).ended:
                summary.failed[seed] = "the episode ended before the handover"
                continue
            expert.take_over(gym.raw_obs, take_over_view(gym.env.plant))
            info = rollout(episode, gym.raw_obs, lambda _: expert.act(gym.raw_obs).astype(np.float32),
                           [Labels(gym, dataset, cameras)]).info
            if info["is_success"]:
                dataset.save_episode()
                summary.kept.append(seed)
            else:
                dataset.clear_episode_buffer()
                summary.failed[seed] = "the expert did not finish every box right"
    finally:
        if dataset.has_pending_frames():
            dataset.clear_episode_buffer()  # the episode under way is not saved
        dataset.finalize()
        summary.frames = dataset.meta.total_frames
        gym.close()
        (root / "meta" / PROVENANCE).write_text(json.dumps(
            {**asdict(config), "kept": summary.kept, "failed": {str(k): v for k, v in summary.failed.items()},
             "handed_over_at": {str(k): v for k, v in summary.handed_over_at.items()}}, indent=1) + "\n")
    return summary
