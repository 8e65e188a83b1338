"""LeRobot plugin hook: importing this registers ColorSort's ``EnvConfig`` (``--env.type=colorsort``)."""

from colorsort.benchmark.lerobot_env import ColorSortEnv

__all__ = ["ColorSortEnv"]
