"""Crashes and interrupts: a worker killed outright loses at most its shard, --resume after any crash completes the
dataset with every episode once, an interrupt never cuts a save short, shards of another run are refused; the
data the same whatever the shard size (the reference is one shard; the runs here shards of 1 or 2 episodes)."""

import json
import signal
import subprocess
import sys
import time
from dataclasses import replace

import pytest
from scale_common import QUIET, SCALE, by_episode_number, kill_worker_of, same_data, same_episodes

from colorsort.cli.collect import main as collect_main
from colorsort.data.collect import collect
from colorsort.data.config import CollectConfig
from colorsort.data.store import MARKER, SHARD_MARKER
from colorsort.executors.base import ExecutorConfig

pytestmark = pytest.mark.slow  # killed workers, interrupted runs


def test_a_local_worker_killed_outright_loses_only_its_shard_and_resume_completes(reference, tmp_path):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    out = tmp_path / "ds"
    killed = []
    # 1 s: a shard of 2 state-only episodes was once recorded within 3 s of its worker starting
    watcher = kill_worker_of(tmp_path / ".ds.staging", "shard-000002", 1.0, killed)
    summary = collect(CollectConfig(out=str(out), executor=ExecutorConfig(workers=2, retries=0), **SCALE), **QUIET)
    watcher.join()
    assert killed and len(summary.errors) == 1 and "SIGKILL" in summary.errors[0]
    assert json.loads((out / MARKER).read_text())["episodes"] == [0, 1]  # the other shard is kept
    assert LeRobotDataset("local/colorsort", root=out).num_episodes == 2

    summary = collect(CollectConfig(out=str(out), executor=ExecutorConfig(workers=2), resume=True, **SCALE), **QUIET)
    assert summary.tried == 2 and summary.kept == 2 and not summary.errors
    same_data(reference, out)


def test_resume_after_the_whole_run_was_killed_keeps_its_finished_shards(reference, tmp_path, capsys):
    """The collector killed outright mid-run (a process of its own); then, in this process, the same command is
    refused without --resume and completes with it."""
    out = tmp_path / "ds"
    argv = ["--out", str(out), "--episodes", "4", "--boxes-per-episode", "2", "--cameras", "none", "--shard-size", "1",
            "--workers", "2"]
    run = subprocess.Popen([sys.executable, "-m", "colorsort.cli.collect", *argv], stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
    staging = tmp_path / ".ds.staging"
    deadline = time.monotonic() + 300
    while len(list(staging.glob(f"shard-*/{SHARD_MARKER}"))) < 2 and time.monotonic() < deadline:
        time.sleep(0.1)
    run.send_signal(signal.SIGKILL)  # the collector itself, mid-run; its workers end with it
    run.wait()
    finished = len(list(staging.glob(f"shard-*/{SHARD_MARKER}")))
    assert 2 <= finished < 4 and not out.exists()

    capsys.readouterr()
    assert collect_main(argv) == 2 and "--resume" in capsys.readouterr().err  # nothing is discarded silently
    assert collect_main(argv + ["--resume"]) == 0
    assert f"{finished} kept from the killed run" in capsys.readouterr().out
    same_data(reference, out)


def test_a_worker_file_killed_mid_write_does_not_stop_resume(reference, tmp_path):
    """Resume past an empty worker file (the last of 3 one-episode shards); one-episode shards give the same
    episodes as the reference's one shard (the shard size never changes the data)."""
    out = tmp_path / "ds"
    staging = tmp_path / ".ds.staging"  # as a run killed between opening and writing a worker file leaves it
    staging.mkdir()
    config = CollectConfig(out=str(out), episodes=3, boxes_per_episode=2, cameras=(), shard_size=1,
                           executor=ExecutorConfig(workers=2))
    (staging / "run.json").write_text(json.dumps({"run": "killed-run", "settings": config.settings()}))
    (staging / "shard-000002.worker.json").write_text("")
    summary = collect(replace(config, resume=True), **QUIET)
    assert summary.kept == 3 and not summary.errors
    assert json.loads((out / MARKER).read_text())["episodes"] == [0, 1, 2]
    same_episodes(reference, out, only=[0, 1, 2])


def test_writes_that_must_appear_whole_leave_no_partial_file(tmp_path):
    from colorsort.data.shards import previous_attempt
    from colorsort.data.store import write_whole

    worker = tmp_path / "shard-000000.worker.json"
    assert previous_attempt(worker) == 0
    write_whole(worker, {"attempt": 3})
    assert previous_attempt(worker) == 3 and [p.name for p in tmp_path.iterdir()] == [worker.name]
    worker.write_text("")  # what an in-place write killed after opening the file left
    assert previous_attempt(worker) == 1


def test_an_interrupt_during_held_interrupts_comes_after_the_block():
    from colorsort.executors.base import held_interrupts

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a Ray worker, or a terminal
    finished = []
    try:
        with pytest.raises(KeyboardInterrupt):
            with held_interrupts():
                signal.raise_signal(signal.SIGINT)
                time.sleep(0.01)
                finished.append(True)
        assert finished == [True] and signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGINT, previous)


def test_a_simulated_interrupt_during_held_interrupts_comes_after_the_block():
    """Ray cancels a running task with a simulated SIGINT (the handler is called; no signal is sent, so a re-sent
    one was lost and a cancelled collection ran to its end, which CI caught): ``_thread.interrupt_main``, from
    another thread as Ray's core worker does it, lands inside the block and is delivered after it, by calling the
    handler. (Ray's cancel end to end: ``test_scale``'s stubborn task and Ctrl-C on Ray.)"""
    import _thread
    import threading

    from colorsort.executors.base import held_interrupts

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a Ray worker
    inside, finished = threading.Event(), []
    canceller = threading.Thread(target=lambda: inside.wait(10) and _thread.interrupt_main())
    canceller.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            with held_interrupts():
                inside.set()
                canceller.join(10)  # the simulated SIGINT has been raised while the block runs
                for _ in range(20):
                    time.sleep(0.01)  # bytecodes run: an unheld interrupt would land here
                finished.append(True)
        assert finished == [True] and signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGINT, previous)


def test_an_interrupt_while_an_episode_saves_keeps_that_episode(reference, monkeypatch, tmp_path):
    """Ray cancels a task with a SIGINT, which can land while LeRobot saves an episode (CI caught a run that
    lost both its shards this way): the save ends first, then the shard stops, every saved episode kept."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from colorsort.data.recorder import record_shard

    save = LeRobotDataset.save_episode

    def interrupted_save(self, *args, **kwargs):
        signal.raise_signal(signal.SIGINT)  # Ray's cancel, as it reaches a task
        return save(self, *args, **kwargs)

    monkeypatch.setattr(LeRobotDataset, "save_episode", interrupted_save)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        config = CollectConfig(out=str(tmp_path / "ds"), **SCALE)
        report = record_shard(config, [0, 1], tmp_path / "shard", lambda r: None)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert report.interrupted and not report.incomplete and report.kept == [0] and report.tried == [0]
    shard = LeRobotDataset(config.repo_id, root=tmp_path / "shard")
    assert shard.meta.total_episodes == 1
    assert shard.meta.total_frames == len(by_episode_number(reference)[0]["action"])


def test_a_shard_from_another_run_or_with_other_settings_is_refused(tmp_path):
    small = dict(episodes=2, cameras=(), shard_size=1)
    settings = CollectConfig(**small).settings()
    collect(CollectConfig(out=str(tmp_path / "ds"), **small), **QUIET)
    staging = tmp_path / ".ds.staging"  # as a killed run of --resume --episodes 6 would leave it
    (staging / "shard-000005" / "meta").mkdir(parents=True)
    (staging / "run.json").write_text(json.dumps({"run": "this-run", "settings": settings}))
    resume = CollectConfig(out=str(tmp_path / "ds"), resume=True, **{**small, "episodes": 6})
    for marker, match in [({"run": "other-run", "settings": settings}, "comes from another run"),
                          ({"run": "this-run", "settings": {**settings, "seed": 9}}, "other settings")]:
        marker.update(tried=[5], kept=[5], failed={})
        (staging / "shard-000005" / SHARD_MARKER).write_text(json.dumps(marker))
        with pytest.raises(ValueError, match=match):
            collect(resume, **QUIET)
    assert json.loads((tmp_path / "ds" / MARKER).read_text())["episodes"] == [0, 1]  # untouched
