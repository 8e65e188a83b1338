"""colorsort-replay re-renders an episode from its states, re-runs its actions, and checks both."""

import numpy as np

from colorsort.cli.replay import main
from colorsort.data.replay import MIN_PSNR_DB, replay
from colorsort.data.video import read_video


def test_state_and_action_replay_reproduce_the_episode(tiny_dataset, tmp_path):
    video, sheet = tmp_path / "ep1.mp4", tmp_path / "ep1.png"
    report = replay(tiny_dataset, 1, "scene", None, str(video), str(sheet), progress=False)
    assert report.state_mismatches == 0  # restored states give back the recorded observation.state exactly
    assert report.min_psnr_db >= MIN_PSNR_DB
    assert report.outcomes == ["placed"] and report.max_state_error == 0.0  # bit for bit, on this machine
    assert read_video(video).shape == (report.frames, 64, 64, 3)
    assert sheet.stat().st_size > 1000


def test_replay_renders_any_camera_at_any_size(tiny_dataset, tmp_path, capsys):
    video = tmp_path / "wrist.mp4"
    assert main([str(tiny_dataset), "--episode", "0", "--camera", "wrist", "--size", "96x128",
                 "--video", str(video)]) == 0
    frames = read_video(video)
    assert frames.shape[1:] == (96, 128, 3) and frames.std() > 10
    assert (tmp_path / "wrist.png").exists()
    out = capsys.readouterr().out
    assert "no frames to compare" in out and "action replay" in out and "FAILED" not in out


def test_replay_of_a_missing_episode_is_an_error(tiny_dataset, capsys):
    assert main([str(tiny_dataset), "--episode", "7"]) == 2
    assert "valid episodes: 0..1" in capsys.readouterr().err


def test_contact_sheet_picks_first_and_last_frames():
    from colorsort.data.video import contact_sheet

    frames = [np.full((30, 40, 3), k, np.uint8) for k in range(50)]
    sheet = contact_sheet(frames, columns=4, rows=2, width=160)
    assert sheet.shape == (60, 160, 3)
    assert sheet[15, 20, 0] == 0 and sheet[45, 140, 0] == 49
