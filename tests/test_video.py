"""Headless video: colorsort-sort films the cell; frames decode back to what was rendered."""

import numpy as np

from colorsort.benchmark.sorting import SortConfig, run_sort
from colorsort.data.video import VideoWriter, read_video


def test_video_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    frames = [np.full((48, 64, 3), c, np.uint8) for c in rng.integers(0, 255, (5, 3))]
    with VideoWriter(tmp_path / "v.mp4", fps=20, crf=10) as video:
        for f in frames:
            video.write(f)
    decoded = read_video(tmp_path / "v.mp4")
    assert decoded.shape == (5, 48, 64, 3)
    assert np.abs(decoded.astype(int) - np.stack(frames)).mean() < 4


def test_sort_films_every_step_with_an_overlay(tmp_path):
    path = tmp_path / "sort.mp4"
    report = run_sort(SortConfig(boxes=1, video=str(path), video_size=(120, 160)), progress=False, log=lambda _: None)
    frames = read_video(path)
    assert frames.shape == (int(round(report.sim_time_s / 0.05)), 120, 160, 3)  # one frame per 20 Hz step
    assert frames[0].std() > 10  # a picture, not a blank frame
    assert frames[:, :12, :80].max() > 230  # the overlay's white text in the top-left corner
    assert path.with_suffix(".png").stat().st_size > 1000  # the contact sheet beside it
