"""LeRobot plugin hook: importing this registers ColorSort's ``EnvConfig`` (``--env.type=colorsort``)."""

from colorsort.envs.lerobot_env import ColorSortEnv

__all__ = ["ColorSortEnv"]
