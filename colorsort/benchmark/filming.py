"""Film an evaluation episode where it runs: the scene camera with an overlay, as H.264 mp4 bytes.

Filming only renders: it reads the simulation and never writes to it, so an episode gives the same
results filmed or not (tested). The overlay shows the sim time, the policy's phase when it has one
(the scripted expert's), the bins' counts, the colour of the next box in play and whether the ray
at the sensor is blocked, and the last boxes to leave play, each with its outcome.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from colorsort.benchmark.gym_env import ColorSortGymEnv
from colorsort.cell.referee import describe_box
from colorsort.config import BIN_COLORS
from colorsort.data.video import VideoWriter, draw_lines

FILM_CAMERA = "scene"
FILM_SIZE = (360, 480)  # (height, width) [px]
EVENTS_SHOWN = 3  # the latest box events written on the frame

GOOD, BAD = (120, 255, 120), (255, 110, 110)  # RGB of an event handled right / wrong


def overlay_lines(env: ColorSortGymEnv, phase: str | None) -> list[str | tuple[str, tuple[int, int, int]]]:
    """What the film writes on the current frame."""
    cell = env.env
    counts = cell.task_info()["bins"]
    lines: list[str | tuple[str, tuple[int, int, int]]] = [
        f"t {cell.cur_time:5.1f} s  step {env.steps}" + (f"  phase: {phase}" if phase else ""),
        "bins: " + "  ".join(f"{c} {counts[c]['count']}" for c in BIN_COLORS),
    ]
    boxes = cell.boxes_in_play()
    nearest = min(boxes, key=lambda b: b.serial).color if boxes else "-"
    lines.append(f"next box: {nearest}  ray: {'blocked' if cell.box_detected else 'clear'}")
    events = cell.events[: env.variant.boxes]
    for event in events[-EVENTS_SHOWN:]:
        text = f"{event.time:5.1f} s  {describe_box(event.color, event.outcome, event.bin)}"
        lines.append((text, GOOD if event.outcome.handled_right else BAD))
    return lines


class EpisodeFilm:
    """One episode's film: ``add`` a frame after the reset and after every step, then ``finish``.

    Args:
        env: the episode's env (its scene camera is rendered at ``size``, apart from the cameras
            the policy sees).
        size: (height, width) of the film [px].
    """

    def __init__(self, env: ColorSortGymEnv, size: tuple[int, int] = FILM_SIZE):
        self.env, self.size = env, size
        self._dir = tempfile.TemporaryDirectory(prefix="colorsort-film-")
        self._writer = VideoWriter(Path(self._dir.name) / "episode.mp4", fps=env.fps)

    def add(self, phase: str | None = None) -> None:
        """Film the env as it is now, with ``phase`` (the policy's, if it has one) in the overlay."""
        h, w = self.size
        frame = self.env.env.camera_image(FILM_CAMERA, w, h)
        self._writer.write(draw_lines(frame, overlay_lines(self.env, phase)))

    def finish(self) -> bytes:
        """The mp4 file's bytes; the temporary file is gone."""
        try:
            self._writer.close()
            return self._writer.path.read_bytes()
        finally:
            self._dir.cleanup()

    def discard(self) -> None:
        """Drop the film (the episode failed to run)."""
        self._writer.close()
        self._dir.cleanup()

