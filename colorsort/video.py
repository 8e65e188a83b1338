"""Headless video: camera frames to H.264 mp4 with PyAV, and PNG stills."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from types import TracebackType

import av
import cv2
import numpy as np


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
        self._stream = None
        self.frames = 0

    def write(self, frame: np.ndarray) -> None:
        """Append one RGB frame; the first frame fixes the size (cropped to even sides for yuv420p)."""
        h, w = frame.shape[0] // 2 * 2, frame.shape[1] // 2 * 2
        if self._container is None:
            self._container = av.open(str(self.path), mode="w")
            self._stream = self._container.add_stream(self.codec, rate=self.fps)
            self._stream.width, self._stream.height = w, h
            self._stream.pix_fmt = "yuv420p"
            self._stream.options = {"crf": str(self.crf)}
        video_frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(frame[:h, :w]), format="rgb24")
        for packet in self._stream.encode(video_frame):
            self._container.mux(packet)
        self.frames += 1

    def close(self) -> None:
        """Flush the encoder and close the file."""
        if self._container is not None:
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


def read_video(path: str | Path) -> np.ndarray:
    """Decode an mp4 into RGB frames, shape (T, H, W, 3) uint8."""
    with av.open(str(path)) as container:
        return np.stack([f.to_ndarray(format="rgb24") for f in container.decode(video=0)])
