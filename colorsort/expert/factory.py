"""The expert for a cell: the stopping belt's or the tracking belt's, calibrated on the env it will drive."""

from __future__ import annotations

from typing import TYPE_CHECKING

from colorsort.errors import ConfigError
from colorsort.expert.base import Expert
from colorsort.expert.calibration import Calibration, sensor_source
from colorsort.expert.config import ExpertConfig, expert_preset
from colorsort.expert.sorter import SortingExpert
from colorsort.expert.tracking import TrackingExpert

__all__ = ["expert_preset", "make_expert"]

if TYPE_CHECKING:
    from colorsort.envs.robosuite_task import ColorSort


def make_expert(env: ColorSort, config: ExpertConfig | None = None) -> Expert:
    """A ``SortingExpert`` on a stopping belt, a ``TrackingExpert`` on a tracking one, calibrated on ``env``;
    ``config`` defaults to the belt's preset (``STOPPING_EXPERT``, ``TRACKING_EXPERT``).

    ``env`` must have an off-screen renderer: the expert sees boxes through the sensor camera.
    Use: ``expert = make_expert(env)``, ``expert.reset(obs)`` after ``env.reset()``, then
    ``action = expert.act(obs)`` every step.
    """
    if not env.has_offscreen_renderer:
        raise ConfigError("The expert needs the sensor camera: make the env with has_offscreen_renderer=True")
    tracking = env.config.tracking
    config = config or expert_preset(tracking)
    size = config.sensor_image_size
    cls = TrackingExpert if tracking else SortingExpert
    return cls(Calibration.from_env(env, (size, size)), sensor_source(env, size), config)
