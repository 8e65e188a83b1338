"""Headless video: camera frames to H.264 mp4 with PyAV, and PNG stills."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING

import cv2
import numpy as np

if TYPE_CHECKING:  # PyAV is imported where a video is written or read: the batched cell's GPU hosts lack it
    import av

from colorsort.errors import ConfigError


class VideoWriter:
    """Write RGB frames (H, W, 3) uint8 to an mp4; use as a context manager.

    Args:
        path: output file; its folder is created.
        fps: frames per second of the video [Hz].
        codec: any encoder PyAV has ("libx264" by default; "libsvtav1" for AV1).
        crf: constant rate factor (lower is better quality, bigger file).
    """

    def __init__(self, path: str | Path, fps: float, codec: str = "libx264", crf: int = 23):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.fps = Fraction(fps).limit_denominator(1000)
        self.codec, self.crf = codec, crf
        self._container: av.container.OutputContainer | None = None
        self._stream: av.VideoStream | None = None
        self.frames = 0

    def write(self, frame: np.ndarray) -> None:
        """Append one RGB frame; the first frame fixes the size (cropped to even sides for yuv420p)."""
        h, w = frame.shape[0] // 2 * 2, frame.shape[1] // 2 * 2
        if self._container is None or self._stream is None:
            import av

            container = av.open(str(self.path), mode="w")
            stream = container.add_stream(self.codec, rate=self.fps)
            if not isinstance(stream, av.VideoStream):
                container.close()
                raise ConfigError(f"codec {self.codec!r} does not encode video")
            stream.width, stream.height = w, h
            stream.pix_fmt = "yuv420p"
            stream.options = {"crf": str(self.crf)}
            self._container, self._stream = container, stream
        import av

        video_frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(frame[:h, :w]), format="rgb24")
        for packet in self._stream.encode(video_frame):
            self._container.mux(packet)
        self.frames += 1

    def close(self) -> None:
        """Flush the encoder and close the file."""
        if self._container is not None and self._stream is not None:
            for packet in self._stream.encode():
                self._container.mux(packet)
            self._container.close()
            self._container = None

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(self, exc_type: type | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self.close()


def save_png(path: str | Path, frame: np.ndarray) -> None:
    """Write an RGB frame (H, W, 3) uint8 as a PNG."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(path), cv2.cvtColor(frame, cv2.COLOR_RGB2BGR)):
        raise OSError(f"could not write {path}")


def draw_lines(frame: np.ndarray, lines: list[str | tuple[str, tuple[int, int, int]]]) -> np.ndarray:
    """A copy of an RGB frame with ``lines`` of text at its top left, outlined so that they read on any
    background; a line is a string (white) or ``(text, rgb)``. The text scales with the frame's height."""
    out = frame.copy()
    scale = out.shape[0] / 480
    for i, line in enumerate(lines):
        text, color = (line, (255, 255, 255)) if isinstance(line, str) else line
        org = (int(10 * scale), int((24 + 22 * i) * scale))
        cv2.putText(out, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.6 * scale, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(out, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.6 * scale, color, 1, cv2.LINE_AA)
    return out


def read_video(path: str | Path) -> np.ndarray:
    """Decode an mp4 into RGB frames, shape (T, H, W, 3) uint8."""
    import av

    with av.open(str(path)) as container:
        frames = [f.to_ndarray(format="rgb24") for f in container.decode(video=0)]
    return np.stack(frames)


def contact_sheet(frames: list[np.ndarray], columns: int = 4, rows: int = 3, fps: float | None = None,
                  width: int = 1280) -> np.ndarray:
    """A grid of ``columns x rows`` frames picked evenly from first to last, for a quick look.

    Args:
        frames: RGB frames (H, W, 3) uint8, all the same size.
        columns, rows: the grid.
        fps: if given, each tile is labelled with its time [s].
        width: width of the sheet [px]; tiles keep the frames' aspect ratio.
    """
    if not frames:
        raise ConfigError("contact_sheet needs at least one frame")
    picks = np.unique(np.linspace(0, len(frames) - 1, min(columns * rows, len(frames))).round().astype(int))
    h, w = frames[0].shape[:2]
    tile_w = width // columns
    tile_h = max(1, round(h * tile_w / w))
    sheet = np.full((tile_h * int(np.ceil(len(picks) / columns)), tile_w * columns, 3), 255, np.uint8)
    for n, k in enumerate(picks):
        tile = cv2.resize(frames[k], (tile_w, tile_h), interpolation=cv2.INTER_AREA)
        if fps:
            label = f"{k / fps:.2f} s"
            cv2.putText(tile, label, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 3, cv2.LINE_AA)
            cv2.putText(tile, label, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
        r, c = divmod(n, columns)
        sheet[r * tile_h : (r + 1) * tile_h, c * tile_w : (c + 1) * tile_w] = tile
    return sheet
