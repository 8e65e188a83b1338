"""Film an evaluation episode where it runs: the scene camera with an overlay, as H.264 mp4 bytes.

Filming only renders: it reads the simulation and never writes to it, so an episode gives the same
results filmed or not (tested). The overlay shows the sim time, the policy's phase when it has one
(the scripted expert's), the bins' counts, the colour of the next box in play and whether the ray
at the sensor is blocked, and the last boxes to leave play, each with its outcome.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from colorsort.cell.referee import Outcome, describe_box
from colorsort.config import BIN_COLORS
from colorsort.data.video import VideoWriter, draw_lines
from colorsort.envs.gym_env import ColorSortGymEnv

FILM_CAMERA = "scene"
FILM_SIZE = (360, 480)  # (height, width) [px]
EVENTS_SHOWN = 3  # the latest box events written on the frame

GOOD, BAD = (120, 255, 120), (255, 110, 110)  # RGB of an event handled right / wrong


Line = str | tuple[str, tuple[int, int, int]]  # a line of the overlay, white or in a colour (RGB)


def overlay_text(time: float, step: int, phase: str | None, bins: dict[str, int], next_box: str | None,
                 detected: bool, events: list[tuple[float, str, Outcome, str | None]]) -> list[Line]:
    """What a film writes on a frame: the sim time [s] and control step, the policy's phase (if any), the boxes
    in each bin, the colour of the next box in play, the ray, and the last ``EVENTS_SHOWN`` of the episode's
    boxes that left play so far, each (time [s], colour, outcome, bin or None). The CPU cell's films and the
    batched cell's (``batched/films.py``) both write it."""
    lines: list[Line] = [
        f"t {time:5.1f} s  step {step}" + (f"  phase: {phase}" if phase else ""),
        "bins: " + "  ".join(f"{c} {bins[c]}" for c in BIN_COLORS),
        f"next box: {next_box or '-'}  ray: {'blocked' if detected else 'clear'}",
    ]
    for t, color, outcome, bin in events[-EVENTS_SHOWN:]:
        lines.append((f"{t:5.1f} s  {describe_box(color, outcome, bin)}", GOOD if outcome.handled_right else BAD))
    return lines


def overlay_lines(env: ColorSortGymEnv, phase: str | None) -> list[Line]:
    """``overlay_text`` for the CPU cell's episode as it is now."""
    cell = env.env
    counts = cell.task_info()["bins"]
    boxes = cell.boxes_in_play()
    nearest = min(boxes, key=lambda b: b.serial).color if boxes else None
    events = [(e.time, e.color, e.outcome, e.bin) for e in cell.events[: env.variant.boxes]]
    return overlay_text(cell.cur_time, env.steps, phase, {c: counts[c]["count"] for c in BIN_COLORS}, nearest,
                        cell.box_detected, events)


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

