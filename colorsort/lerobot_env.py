"""LeRobot's ``EnvConfig`` for ColorSort, so that LeRobot's own tools evaluate policies on it.

``lerobot-eval`` finds it through LeRobot's plugin mechanism::

    lerobot-eval --env.discover_packages_path=colorsort --env.type=colorsort \\
        --env.task=ColorSort-Jitter-v0 --policy.path=outputs/train/act/checkpoints/last/pretrained_model \\
        --eval.n_episodes=10 --eval.batch_size=1 --policy.device=cpu

``--env.task`` is a Gymnasium id without the ``colorsort/`` namespace (``ColorSort-v0`` or a
variant's, see ``colorsort-eval --list``); ``--env.cameras`` and ``--env.image_size`` must match
the dataset the policy was trained on.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig
from lerobot.utils.constants import ACTION, OBS_ENV_STATE, OBS_IMAGES, OBS_STATE

from colorsort.config import COLORS


@EnvConfig.register_subclass("colorsort")
@dataclass
class ColorSortEnv(EnvConfig):
    """ColorSort for LeRobot: ``task`` is the Gymnasium id without its namespace."""

    task: str | None = "ColorSort-v0"
    fps: int = 20
    cameras: str = "scene,wrist"  # comma-separated, as recorded by colorsort-collect --cameras
    image_size: int = 128  # square camera images [px]
    robot_joints: int = 6  # 6 for the IRB 140 and UR5e, 7 for the Panda
    episode_length: int | None = None  # steps before truncation; default: the variant's time limit
    features: dict[str, PolicyFeature] = field(default_factory=dict)
    features_map: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = self.robot_joints
        self.features = {
            ACTION: PolicyFeature(type=FeatureType.ACTION, shape=(n + 2,)),
            "agent_pos": PolicyFeature(type=FeatureType.STATE, shape=(2 * n + 11,)),
            "environment_state": PolicyFeature(type=FeatureType.ENV, shape=(len(COLORS) + 8,)),
        }
        self.features_map = {ACTION: ACTION, "agent_pos": OBS_STATE, "environment_state": OBS_ENV_STATE}
        for cam in self.camera_list:
            key = f"pixels/{cam}"
            self.features[key] = PolicyFeature(type=FeatureType.VISUAL, shape=(self.image_size, self.image_size, 3))
            self.features_map[key] = f"{OBS_IMAGES}.{cam}"

    @property
    def camera_list(self) -> tuple[str, ...]:
        return tuple(c.strip() for c in self.cameras.split(",") if c.strip())

    @property
    def package_name(self) -> str:
        return "colorsort"

    @property
    def gym_id(self) -> str:
        return f"colorsort/{self.task}"

    @property
    def gym_kwargs(self) -> dict:
        return {"cameras": self.camera_list, "image_size": (self.image_size, self.image_size), "fps": self.fps,
                "max_episode_steps": self.episode_length}
