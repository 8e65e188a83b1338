"""The cell's cameras: their names, off-screen rendering right side up, and the renderer's settings.

ColorSort names its cameras ``scene``, ``sensor`` (the colour sensor over the pick point),
``wrist`` and ``snapshot`` (the sensor's view taken when the ray fires, held: ``snapshot.py``);
robosuite prefixes the gripper's camera, so ``wrist`` is ``gripper0_right_wrist`` in
the compiled model. Rendering goes through robosuite's ``MjSim``, which owns the GL context.
"""

from __future__ import annotations

import time
import xml.etree.ElementTree as ET
from collections.abc import Callable
from typing import Any

import mujoco
import numpy as np
from robosuite.utils.observables import sensor

from colorsort.cell.snapshot import SNAPSHOT, SOURCE, Snapshot
from colorsort.errors import ConfigError, UnknownName

PHYSICAL_CAMERAS: tuple[str, ...] = ("scene", "sensor", "wrist")  # rendered live; an env's cameras by default
CAMERAS: tuple[str, ...] = (*PHYSICAL_CAMERAS, SNAPSHOT)
DEFAULT_CAMERAS: tuple[str, ...] = ("scene", "wrist")  # what a dataset records and a policy sees by default
DEFAULT_IMAGE_SIZE: tuple[int, int] = (128, 128)  # (height, width) [px] of every camera by default
WRIST_CAMERA_MJCF = "gripper0_right_wrist"  # robosuite prefixes the gripper's camera name


def parse_cameras(text: str) -> tuple[str, ...]:
    """Camera names from a command line's comma-separated list; "none" (or nothing) for no cameras."""
    if text.strip() == "none":
        return ()
    return tuple(c.strip() for c in text.split(",") if c.strip())


def check_cameras(cameras: list[str] | tuple[str, ...]) -> None:
    """``ValueError`` naming the valid cameras unless every name is one of ``CAMERAS``."""
    unknown = [c for c in cameras if c not in CAMERAS]
    if unknown:
        raise UnknownName("camera(s)", unknown, list(CAMERAS), "cameras")


def mjcf_name(camera: str) -> str:
    """The compiled model's name of ColorSort camera ``camera``."""
    return WRIST_CAMERA_MJCF if camera == "wrist" else camera


def alias(mjcf: str) -> str:
    """ColorSort's name of the compiled model's camera ``mjcf``."""
    return "wrist" if mjcf == WRIST_CAMERA_MJCF else mjcf


def tune_visual(root: ET.Element) -> None:
    """Renderer settings in a task's MJCF ``root``: no multisampling off screen (3x faster on a CPU,
    and images stay crisp at 128 px), and a dim headlight without glare: MuJoCo's default (diffuse
    0.4, specular 0.5) shines straight down the sensor camera's axis and washes box colours out."""
    visual = root.find("visual")
    if visual is None:
        visual = root.makeelement("visual", {})
        root.append(visual)
    quality = visual.find("quality")
    if quality is None:
        quality = visual.makeelement("quality", {})
        visual.append(quality)
    quality.set("offsamples", "0")
    headlight = visual.find("headlight")
    if headlight is None:
        headlight = visual.makeelement("headlight", {})
        visual.append(headlight)
    headlight.attrib.update(ambient="0.15 0.15 0.15", diffuse="0.15 0.15 0.15", specular="0 0 0")


class CameraRenderer:
    """Renders the cell's cameras through a robosuite ``MjSim``, timing what it spends, and holds the
    snapshot camera's photo.

    Attributes:
        seconds: [s] wall time spent rendering, for benchmarks.
        snapshot: the snapshot camera's latch (``snapshot.py``).
        effect: what a held-out shift does to every rendered colour image, ``effect(camera, image)``, or None.
    """

    def __init__(self) -> None:
        self.seconds = 0.0
        self.snapshot = Snapshot()
        self.effect: Callable[[str, np.ndarray], Any] | None = None

    def observe_ray(self, sim, box_detected: bool) -> None:
        """One observation of the ray, before the cameras': on a box's arrival the snapshot camera
        takes its photo (the sensor's view) at every size it was asked for."""
        self.snapshot.observe(box_detected, lambda width, height: self.image(sim, SOURCE, width, height))

    @staticmethod
    def hide_rangefinder(sim) -> None:
        """Hide the rangefinder's drawn ray, which would show up in the images (once a context exists)."""
        context = sim._render_context_offscreen  # robosuite creates it on the first render
        if context is not None:
            context.vopt.flags[mujoco.mjtVisFlag.mjVIS_RANGEFINDER] = 0

    def image(self, sim, camera: str, width: int, height: int, depth: bool = False):
        """Camera ``camera`` now: (H, W, 3) uint8 RGB, right side up; with ``depth`` also (H, W, 1) [m]."""
        check_cameras([camera])
        if camera == SNAPSHOT:
            if depth:
                raise ConfigError("The snapshot camera holds a colour photo, no depth; render 'sensor' for depth")
            return self.snapshot.image(width, height)
        start = time.perf_counter()
        name = mjcf_name(camera)
        if sim._render_context_offscreen is None:
            sim.render(camera_name=name, width=width, height=height)
            self.hide_rangefinder(sim)
        img = sim.render(camera_name=name, width=width, height=height, depth=depth)
        self.seconds += time.perf_counter() - start
        if depth:
            rgb, d = img
            return self._effect(camera, np.ascontiguousarray(rgb[::-1])), np.ascontiguousarray(d[::-1, :, None])
        return self._effect(camera, np.ascontiguousarray(img[::-1]))

    def _effect(self, camera: str, image: np.ndarray) -> np.ndarray:
        return image if self.effect is None else self.effect(camera, image)


def free_context(sim) -> None:
    """Free ``sim``'s offscreen GL context now: it and the sim refer to each other, so without this only a full
    garbage collection would free it."""
    context = sim._render_context_offscreen
    if context is not None:
        context.sim = None
        sim._render_context_offscreen = None
        del context  # the last reference: its __del__ frees MuJoCo's and the GL context


def camera_sensors(render: Callable, mjcf: str, width: int, height: int, depth: bool, modality: str = "image"):
    """robosuite sensors for camera ``mjcf``, named by its ColorSort alias (``<alias>_image``, and
    ``<alias>_depth`` with ``depth``); ``render(alias, width, height, depth=...)`` draws the images."""
    name = alias(mjcf)

    @sensor(modality=modality)
    def camera_rgb(obs_cache):
        if depth:
            rgb, d = render(name, width, height, depth=True)
            obs_cache[f"{name}_depth"] = d
            return rgb
        return render(name, width, height)

    sensors, names = [camera_rgb], [f"{name}_image"]
    if depth:

        @sensor(modality=modality)
        def camera_depth(obs_cache):
            return obs_cache.get(f"{name}_depth", np.zeros((height, width, 1)))

        sensors.append(camera_depth)
        names.append(f"{name}_depth")
    return sensors, names
