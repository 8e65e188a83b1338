"""The triggered colour photo: the sensor camera's image taken when the ray starts seeing a box, held.

Industrial vision sensors are triggered by a photoeye: they take one picture as a part arrives and
the controller keeps it. ColorSort's ``snapshot`` camera is that picture. It looks from the sensor
camera's pose (the arena has a camera named ``snapshot`` there), but its image changes only on a
rising edge of the ray (``box_detected`` false at the previous observation, true at this one): the
cell renders the sensor's view then and returns it at every observation until the next box
arrives. Before the first arrival of an episode it is black.

It is how a policy that reads one frame at a time (ACT) still sees the colour of the box it is
carrying: once the cup is over the box the live sensor camera sees the arm, and the wrist camera
sees the held box from wherever the cup sealed on it. The photo is a function of the episode's
history, not of the instant: ``reset()`` clears it; ``set_sim_state`` leaves it as it was, so a
replay that restores an episode's states in order, observing each, takes the same photos.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

SNAPSHOT = "snapshot"  # the camera's ColorSort (and MJCF) name
SOURCE = "sensor"  # the camera whose view it holds


class Snapshot:
    """The held photo at every size asked for.

    A size is rendered at each trigger once it was asked for (``image``); asking for a new size
    after a trigger returns black until the next one, so ask before the episode's first box (an
    env does: it samples every observation at reset).
    """

    def __init__(self) -> None:
        self._images: dict[tuple[int, int], np.ndarray] = {}  # (width, height) -> (H, W, 3) uint8
        self._saw_box = False
        self.triggers = 0  # photos taken this episode

    def clear(self) -> None:
        """A new episode: black at every size, no box seen."""
        for size, img in self._images.items():
            self._images[size] = np.zeros_like(img)
        self._saw_box = False
        self.triggers = 0

    def observe(self, box_detected: bool, render: Callable[[int, int], np.ndarray]) -> None:
        """One observation of the ray; on its rising edge ``render(width, height)`` takes the photo
        (the source camera's RGB image, right side up) at every size asked for so far."""
        if box_detected and not self._saw_box:
            self.triggers += 1
            for width, height in self._images:
                self._images[width, height] = render(width, height)
        self._saw_box = bool(box_detected)

    def image(self, width: int, height: int) -> np.ndarray:
        """The held photo at ``width`` x ``height`` [px]: (H, W, 3) uint8, black before the first trigger."""
        if (width, height) not in self._images:
            self._images[width, height] = np.zeros((height, width, 3), np.uint8)
        return self._images[width, height].copy()
