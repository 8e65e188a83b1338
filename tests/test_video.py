"""Headless video: the demo films the cell; frames decode back to what was rendered."""

import numpy as np

from colorsort.demo import main as demo_main
from colorsort.video import VideoWriter, read_video


def test_video_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    frames = [np.full((48, 64, 3), c, np.uint8) for c in rng.integers(0, 255, (5, 3))]
    with VideoWriter(tmp_path / "v.mp4", fps=20, crf=10) as video:
        for f in frames:
            video.write(f)
    decoded = read_video(tmp_path / "v.mp4")
    assert decoded.shape == (5, 48, 64, 3)
    assert np.abs(decoded.astype(int) - np.stack(frames)).mean() < 4


def test_demo_writes_video_and_still(tmp_path):
    assert demo_main(["--seconds", "2", "--out", str(tmp_path), "--width", "160", "--height", "120"]) == 0
    frames = read_video(tmp_path / "cell.mp4")
    assert frames.shape == (40, 120, 160, 3)
    assert (tmp_path / "cell.png").stat().st_size > 1000
    assert frames[0].std() > 10  # a picture, not a blank frame
