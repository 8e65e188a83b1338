"""Randomised sensor-camera views of boxes with their ground truth, for measuring the colour sensor.

A view is rendered from the task's own scene: boxes are set on the belt where the ray sensor stops
them (or entering the view, or with a second box queued behind), the lights are set to a
``Lighting`` condition, and sensor effects are added to the image.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from colorsort.cell.lighting import LightRig, sensor_effects
from colorsort.config import Lighting
from colorsort.envs.robosuite_task import ColorSort
from colorsort.errors import ConfigError
from colorsort.expert.perception import CameraModel, wrap_quarter_turn

LAYOUTS: tuple[str, ...] = ("single", "partial", "two_boxes")


@dataclass(frozen=True)
class View:
    """A rendered image and the truth about the box the sensor should report.

    Attributes:
        image: (H, W, 3) uint8 RGB, right side up.
        color: the box's true colour.
        center: true centre of its top face [m], (3,).
        yaw: its true yaw [rad] in [-pi/4, pi/4).
        complete: whether the whole box is in view.
    """

    image: np.ndarray
    color: str
    center: np.ndarray
    yaw: float
    complete: bool


class ViewSampler:
    """Renders views from the sensor camera of ``env`` (which must have an offscreen renderer).

    Args:
        env: a reset ColorSort env; its boxes are rearranged and its lights changed.
        width, height: image size [px].
        lateral_jitter: max |offset| of a box from the belt centre line [m].
    """

    def __init__(self, env: ColorSort, width: int = 128, height: int = 128, lateral_jitter: float = 0.06):
        self.env = env
        self.width, self.height = width, height
        self.lateral_jitter = lateral_jitter
        self.rig = LightRig(env.mj_model)
        env.sim.forward()
        self.camera = CameraModel.from_sim(env.mj_model, env.mj_data, "sensor", width, height)

    def sample(self, color: str, lighting: Lighting, layout: str, rng: np.random.Generator,
               other_colors: tuple[str, ...] = ("red", "green", "blue")) -> View:
        """One random view of a ``color`` box; ``layout`` is one of ``LAYOUTS``."""
        if layout not in LAYOUTS:
            raise ConfigError(f"Unknown layout {layout!r}. Valid layouts: {list(LAYOUTS)}")
        env, L = self.env, self.env.layout
        for box in env.boxes_in_play():
            env.remove_box(box)
        half = L.box_size / 2
        yaw = rng.uniform(-np.pi / 4, np.pi / 4)
        y = L.belt_y + rng.uniform(-self.lateral_jitter, self.lateral_jitter)
        reach = half * (abs(np.cos(yaw)) + abs(np.sin(yaw)))  # centre to leading corner along x
        top_z = L.belt_top_z + L.box_size
        # the upstream edge of the view
        x_edge = self.camera.pixel_to_plane(np.array([[self.width, self.height / 2]]), top_z)[0, 0]
        if layout == "partial":
            x = x_edge + rng.uniform(-0.3, 0.3) * L.box_size  # 20% to 80% of the box in view
        else:
            x = L.sensor_x + reach + rng.uniform(0.0, 0.005)
        env.put_box(color, x, y, yaw)
        if layout == "two_boxes":
            yaw2 = rng.uniform(-np.pi / 4, np.pi / 4)
            reach2 = half * (abs(np.cos(yaw2)) + abs(np.sin(yaw2)))
            gap = rng.uniform(0.0, 0.08)
            y2 = L.belt_y + rng.uniform(-self.lateral_jitter, self.lateral_jitter)
            env.put_box(str(rng.choice(other_colors)), x + reach + gap + reach2, y2, yaw2)
        self.rig.apply(lighting)
        image = np.ascontiguousarray(env.sim.render(camera_name="sensor", width=self.width, height=self.height)[::-1])
        self.rig.restore()
        image = sensor_effects(image, lighting, rng)
        complete = layout != "partial" or x + reach < x_edge
        center = np.array([x, y, top_z])
        return View(image, color, center, wrap_quarter_turn(yaw), complete)
