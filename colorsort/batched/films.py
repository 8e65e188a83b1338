"""Films of the batched cell's episodes, as the CPU cell's look: recorded on the device, drawn on the host.

Rendering every world's film camera at film size on the device would cost more than the evaluation
(thousands of 480x360 images a step), and the films a report keeps are chosen after the episodes end
(failures first, ``report_page.choose_films``). So while a wave runs, ``WaveRecording`` keeps on the
device what a frame needs from each world at each control step (its ``qpos`` and its boxes' status,
colour, serial and bin, the ray); when the wave ends, the episodes a report may keep are copied to the
host (``keep``) and the rest dropped. ``FilmViewer`` then draws a kept episode with the CPU cell's own
renderer: a ColorSort env of the variant, its state set to the world's at each step, its lights to the
episode's, its scene camera at ``filming.FILM_SIZE`` under ``filming.overlay_text``. A film is the same
picture the CPU cell's film of that state would be; the state is the batched cell's (float32 physics).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
import warp as wp

from colorsort.batched.cell import BatchedCell
from colorsort.batched.kernels import IN_BIN, IN_PLAY
from colorsort.batched.schedule import COLOR_NAMES, episode_draws
from colorsort.batched.spec import CellSpec
from colorsort.benchmark.episode_result import EpisodeResult
from colorsort.benchmark.filming import FILM_CAMERA, FILM_SIZE, overlay_text
from colorsort.benchmark.report_page import SUCCESSES_FILMED
from colorsort.cell.lighting import LightRig
from colorsort.cell.referee import Outcome
from colorsort.config import BIN_COLORS, COLORS
from colorsort.data.video import VideoWriter, draw_lines
from colorsort.errors import ConfigError
from colorsort.variants import Variant


@dataclass(frozen=True)
class WorldTrack:
    """One world's episode on the host, a row per frame (the reset, then each control step): ``qpos``
    (T, nq), and per pool box ``status``, ``color``, ``serial``, ``bin`` (T, pool) and ``detected`` (T,); its
    boxes that left play, each (time [s], colour, outcome, bin or None)."""

    seed: int
    events: list
    qpos: np.ndarray
    status: np.ndarray
    color: np.ndarray
    serial: np.ndarray
    bin: np.ndarray
    detected: np.ndarray


class WaveRecording:
    """Every world's frames of one wave, kept on the cell's device until ``keep`` copies some to the host."""

    def __init__(self, cell: BatchedCell):
        self.cell = cell
        self.frames: list[tuple] = []

    def add(self) -> None:
        """The cell as it is now (after a reset or a control step)."""
        c = self.cell
        small = lambda a: wp.to_torch(a).to(torch.int16)  # noqa: E731  (codes, colours, serials, bins: small)
        self.frames.append((wp.to_torch(c.d.qpos).clone(), small(c.status), small(c.color), small(c.serial),
                            small(c.bin_of), wp.to_torch(c.detected).to(torch.bool)))

    def keep(self, worlds: list[int], results: list[EpisodeResult]) -> list[WorldTrack]:
        """The tracks of ``worlds``, world ``worlds[i]`` up to the last step of its episode ``results[i]``
        (``evaluate.episode_result``'s, whose boxes give the events)."""
        index = torch.as_tensor(worlds, dtype=torch.long, device=self.frames[0][0].device)
        rows = [torch.stack([f[k][index] for f in self.frames]).cpu().numpy() for k in range(6)]  # (T, worlds, ...)
        tracks = []
        for i, result in enumerate(results):
            end = result.steps + 1
            events = [(b["time"], b["color"], Outcome(b["outcome"]), b["bin"]) for b in result.boxes]
            qpos, *per_box = (r[:end, i] for r in rows)
            tracks.append(WorldTrack(result.seed, events, qpos.astype(np.float64), *per_box))
        return tracks


def wanted(results: list[EpisodeResult], limit: int | None, have: tuple[int, int]) -> tuple[list[int], tuple[int, int]]:
    """Which of a wave's episode results (seed order) a report may still keep, given the failures and successes
    kept from earlier waves (``have``), and the counts with them: ``choose_films``'s order, failures first,
    successes by seed."""
    failures, successes = have
    keep_successes = SUCCESSES_FILMED if limit is None else limit
    chosen = []
    for i, r in enumerate(results):
        if not r.success and (limit is None or failures < limit):
            chosen.append(i)
            failures += 1
        elif r.success and successes < keep_successes:
            chosen.append(i)
            successes += 1
    return chosen, (failures, successes)


class FilmViewer:
    """Draws ``WorldTrack``s of one variant with the CPU cell's renderer.

    Args:
        spec: the batched cell's model (its box geoms; the viewer's model must be the same).
        variant: the benchmark variant (each episode's lights come from its seed).
        size: (height, width) of the films [px].
    """

    def __init__(self, spec: CellSpec, variant: Variant, size: tuple[int, int] = FILM_SIZE):
        from colorsort.envs.gym_env import ColorSortGymEnv

        self.spec, self.variant, self.size = spec, variant, size
        self.env = ColorSortGymEnv(variant.name, cameras=(), render_mode="rgb_array", fps=round(spec.control_freq))
        self.cell = self.env.env
        model = self.cell.sim.model._model
        if (model.nq, model.ngeom) != (spec.model.nq, spec.model.ngeom):
            raise ConfigError(f"the viewer's model ({model.nq} qpos, {model.ngeom} geoms) is not the batched "
                              f"cell's ({spec.model.nq}, {spec.model.ngeom})")
        self.rig = LightRig(model)
        self.palette = np.array(list(COLORS.values()))
        self.fps = self.env.fps

    def film(self, track: WorldTrack) -> bytes:
        """The mp4 bytes of ``track``, a frame per control step."""
        model, data = self.cell.sim.model._model, self.cell.sim.data._data
        self.rig.apply(episode_draws(self.variant, track.seed, 1).lighting)
        geoms = np.asarray(self.spec.box_geom)
        h, w = self.size
        with tempfile.TemporaryDirectory(prefix="colorsort-film-") as folder:
            writer = VideoWriter(Path(folder) / "episode.mp4", fps=self.fps)
            try:
                for k in range(len(track.qpos)):
                    data.qpos[:] = track.qpos[k]
                    model.geom_rgba[geoms] = self.palette[track.color[k]]
                    self.cell.sim.forward()
                    frame = self.cell.camera_image(FILM_CAMERA, w, h)
                    writer.write(draw_lines(frame, self._overlay(track, k, k / self.fps)))
            finally:
                writer.close()
            return writer.path.read_bytes()

    @staticmethod
    def _overlay(track: WorldTrack, k: int, now: float) -> list:
        status, serial = track.status[k], track.serial[k]
        bins = {c: int(((status == IN_BIN) & (track.bin[k] == i)).sum()) for i, c in enumerate(BIN_COLORS)}
        in_play = np.flatnonzero(status == IN_PLAY)
        nearest = COLOR_NAMES[track.color[k][in_play[np.argmin(serial[in_play])]]] if len(in_play) else None
        so_far = [e for e in track.events if e[0] <= now + 1e-9]
        return overlay_text(now, k, None, bins, nearest, bool(track.detected[k]), so_far)

    def close(self) -> None:
        self.env.close()


class Filming:
    """The films an evaluation's report may keep, gathered wave by wave (``run_waves``) and drawn at the end.

    Args:
        viewer: draws the films.
        limit: ``--videos`` (films per variant, failures first); None: every failure and the first
            ``SUCCESSES_FILMED`` successes.
    """

    def __init__(self, viewer: FilmViewer, limit: int | None):
        self.viewer, self.limit = viewer, limit
        self.tracks: dict[int, WorldTrack] = {}  # seed -> track
        self.kept = (0, 0)  # failures, successes

    def wave_ended(self, recording: WaveRecording, results: list[EpisodeResult]) -> None:
        """Keep what the report may want of a wave whose worlds ``0..len(results)-1`` ran ``results``."""
        chosen, self.kept = wanted(results, self.limit, self.kept)
        if chosen:
            for track in recording.keep(chosen, [results[i] for i in chosen]):
                self.tracks[track.seed] = track

    def films(self, seeds: list[int]) -> dict[int, bytes]:
        """The mp4 bytes of the kept episodes ``seeds``, by seed."""
        return {seed: self.viewer.film(self.tracks[seed]) for seed in seeds}
