"""Collection and evaluation on Ray: the same data and numbers as on local processes, a killed worker retried, a
cancel that stops a task or reports it stopped, Ctrl-C, SLURM's batch script, the docs' Ray commands. One Ray cluster
(2 CPUs) for the module, started by this process; its workers, once they have imported ColorSort and LeRobot, serve
every test after the first that uses it (a new process joining would be a new Ray job with workers of its own)."""

import json
import os
import re
import shlex
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from scale_common import QUIET, SCALE, kill_worker_of, same_episodes

from colorsort.benchmark.evaluate import run_evaluation
from colorsort.data.collect import collect
from colorsort.data.config import CollectConfig
from colorsort.data.store import MARKER
from colorsort.data.video import read_video
from colorsort.executors.base import ExecutorConfig

pytestmark = pytest.mark.slow  # Ray clusters, killed workers, interrupted runs

ray = pytest.importorskip("ray")


@pytest.fixture(scope="module")
def cluster() -> str:
    """A Ray cluster started by this process; its address, for other processes to join (``--address``)."""
    ray.init(address="local", num_cpus=2, include_dashboard=False, logging_level="WARNING",
             runtime_env={"env_vars": {"MUJOCO_GL": os.environ["MUJOCO_GL"], "HF_HUB_OFFLINE": "1"}})
    yield ray.get_runtime_context().gcs_address
    ray.shutdown()


def documented_ray_command(program: str) -> list[str]:
    """docs/scaling.md's command that runs ``program`` on Ray, verbatim."""
    page = (Path(__file__).resolve().parents[1] / "docs" / "scaling.md").read_text()
    (line,) = [line for line in page.splitlines() if line.startswith(f"{program} ") and "--executor ray" in line]
    return shlex.split(line)


def test_the_generated_slurm_script_runs_a_ray_cluster_and_the_docs_eval_command(tmp_path):
    """The batch script on a one-node stand-in for SLURM (srun runs its command here, scontrol names this host),
    its command the docs' colorsort-eval on Ray, verbatim: a Ray head starts and the expert's episodes run there.
    First in the module: its head is the only Ray cluster on the machine (the module's starts after it). The job's
    home is new, as on a machine where Ray never ran: the script makes the token its cluster authenticates with."""
    shims = tmp_path / "bin"
    shims.mkdir()
    (shims / "srun").write_text('#!/bin/bash\n'
                                'while [[ $# -gt 0 && $1 == -* ]]; do [[ $1 == -w ]] && shift; shift; done\n'
                                'exec "$@"\n')
    (shims / "scontrol").write_text("#!/bin/bash\nhostname\n")
    for shim in shims.iterdir():
        shim.chmod(0o755)
    script = tmp_path / "job.sbatch"
    subprocess.run([str(Path(sys.executable).parent / "colorsort-slurm"), "--nodes", "1", "--cpus-per-node", "2",
                    "--port", "6391", "--out", str(script), "--", *documented_ray_command("colorsort-eval")],
                   check=True, capture_output=True)
    home = tmp_path / "home"
    home.mkdir()
    env = {**os.environ, "PATH": f"{shims}:{os.environ['PATH']}", "SLURM_JOB_NODELIST": "node1", "HOME": str(home)}
    job = subprocess.run(["bash", str(script)], env=env, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert job.returncode == 0, job.stdout[-3000:] + job.stderr[-3000:]
    assert (home / ".ray" / "auth_token").stat().st_size > 0
    assert "--address" in script.read_text() and "ray start --head" in script.read_text()
    assert re.search(r"episodes\s+2\b", job.stdout) and re.search(r"success rate\s+100\.0%", job.stdout), job.stdout


def test_a_ray_cluster_records_the_same_dataset_and_a_killed_worker_is_retried(reference, cluster, tmp_path):
    """The same episodes as local processes (an episode's data depends on its seed alone), every one once, though a
    worker was killed outright mid-shard and its shard run again."""
    out = tmp_path / "ds"
    killed = []
    watcher = kill_worker_of(tmp_path / ".ds.staging", "shard-000002", 3.0, killed)
    summary = collect(CollectConfig(out=str(out), executor=ExecutorConfig("ray", 2), **SCALE), **QUIET)
    watcher.join()
    assert killed and summary.retried == 1 and not summary.errors
    assert summary.kept == 4 and summary.dataset_episodes == 4  # every episode, once
    assert json.loads((out / MARKER).read_text())["episodes"] == [0, 1, 2, 3]
    same_episodes(reference, out)


def test_a_task_its_cancel_does_not_stop_is_reported_stopped_never_ok(cluster):
    """A task that outlives its cancel (here: one that swallows KeyboardInterrupt) is killed after the executor's
    wait and reported stopped with why, never ok with no value: a Ctrl-C'd run must not read as finished."""
    from colorsort.executors.base import Task
    from colorsort.executors.ray import RayExecutor

    def stubborn(arg, ctx):
        ctx.send("started")
        until = time.monotonic() + 120
        while time.monotonic() < until:
            try:
                time.sleep(0.1)
            except KeyboardInterrupt:
                pass
        return "ran to its end"

    def ctrl_c(message):
        raise KeyboardInterrupt  # as a terminal's Ctrl-C reaches the caller's loop

    started = time.monotonic()
    [result] = RayExecutor(ExecutorConfig("ray", workers=1), {}, cancel_wait_s=3.0).run(
        [Task("stubborn", stubborn, None)], on_message=ctrl_c)
    assert result.stopped and not result.ok and result.value is None
    assert "after its cancel" in (result.error or "")
    assert time.monotonic() - started < 60


def test_runs_of_one_driver_share_its_message_queue_and_read_only_their_own_messages(cluster):
    """The queue is an actor (a worker process): made once per driver and cluster. A message an earlier run's task
    sent after its run ended (a cancelled one, say) is not counted by the next run."""
    from colorsort.executors.base import Task
    from colorsort.executors.ray import RayExecutor, message_queue

    def echo(arg, ctx):
        ctx.send(arg)
        return arg

    executor = RayExecutor(ExecutorConfig("ray", workers=1), {})
    heard = []
    [first] = executor.run([Task("t", echo, 1)], on_message=heard.append)
    queue = message_queue()
    queue.put(("an-earlier-run", "start", "t", None))  # as a stopped task of another run might still send
    queue.put(("an-earlier-run", "message", "t", "stale"))
    [second] = executor.run([Task("t", echo, 2)], on_message=heard.append)
    assert (first.value, first.attempts, second.value, second.attempts) == (1, 1, 2, 1)
    assert heard == [1, 2] and message_queue() is queue


def test_an_evaluation_on_ray_gives_the_local_numbers_and_films_each_episode_where_it_runs(cluster, tmp_path):
    """Every episode's report (outcomes, boxes, cycle times) as on this process; its film made in the Ray worker.
    Whole episodes on Ray, the expert sorting all: the SLURM test's docs command."""
    kwargs = dict(episodes=2, image_size=(32, 32), cameras=("scene",), progress=False, episode_length=30)
    local = run_evaluation("expert", ["default"], **kwargs)
    spread = run_evaluation("expert", ["default"], **kwargs, executor=ExecutorConfig("ray", 2), shard_size=1,
                            film=True)
    assert local.reports == spread.reports
    assert sorted(spread.films) == [("default", 10000), ("default", 10001)]
    for (_, seed), video in spread.films.items():  # mp4 files of the reset and every step, made in the Ray workers
        (tmp_path / f"{seed}.mp4").write_bytes(video)
        assert video[4:8] == b"ftyp" and len(read_video(tmp_path / f"{seed}.mp4")) == 31


def test_a_sweeps_episodes_reach_its_journal_from_ray_workers_as_they_finish(cluster):
    """Each finished episode of a sweep on Ray comes back through the executor's messages (what the journal writes,
    ``--resume``) and the reports are those of this process."""
    from colorsort.benchmark.shift_sweep import run_sweep, sweep_arms

    arms, seen = sweep_arms(2, 1, (2,), ("image-noise",)), []
    kwargs = dict(episode_length=10, progress=False)
    spread = run_sweep("expert", "default", arms, executor=ExecutorConfig("ray", 2), shard_size=1,
                       on_episode=lambda shift, result: seen.append((shift, result.seed)), **kwargs)
    assert sorted(seen) == [("image-noise:2", 30000), ("image-noise:2", 30001), ("none", 30000), ("none", 30001)]
    assert spread == run_sweep("expert", "default", arms, **kwargs)


def test_the_docs_collection_on_ray_works_as_written(cluster, tmp_path, monkeypatch, capsys):
    """docs/scaling.md's colorsort-collect on Ray, its argv to the console script's ``main`` in this process: it runs
    on the module's cluster (as on any cluster ``ray.init`` finds; starting one: the SLURM test's head)."""
    from colorsort.cli.collect import main

    argv = documented_ray_command("colorsort-collect")
    monkeypatch.chdir(tmp_path)
    assert main(argv[1:]) == 0
    assert "on 2 ray workers; retried 0" in capsys.readouterr().out
    out = tmp_path / argv[argv.index("--out") + 1]
    assert json.loads((out / MARKER).read_text())["episodes"] == [0, 1]


def test_ctrl_c_on_ray_keeps_every_finished_episode_and_resume_completes(cluster, reference, tmp_path, capsys,
                                                                           monkeypatch):
    """Ctrl-C (SIGINT to this process, Python's own handler) to colorsort-collect whose tasks run on Ray: every
    finished episode is kept and it says so; --resume on the same cluster completes the dataset. (Local processes:
    test_collect's interrupted runs.) One shard of 8 episodes on one Ray worker: the interrupt comes once the
    driver hears that the first episode is saved (not when a file of that save appears: a loaded machine cut in
    with nothing kept), 7 to go. A loaded 2-core machine once took so long to deliver the cancel that a shard of 4
    (3 to go) finished before it did (a cancel has taken 40 s to reach a task there). On a machine loaded enough
    that even 7 episodes end first, the run is complete and exits 0 as it should: the test checks that and is
    skipped, for there is nothing to resume."""
    from colorsort.cli.collect import main
    from colorsort.data import collect as collect_module

    out = tmp_path / "ds"
    argv = ["--out", str(out), "--episodes", "8", "--boxes-per-episode", "2", "--cameras", "none", "--shard-size", "8",
            "--workers", "1", "--executor", "ray"]
    first_saved = threading.Event()
    on_episode = collect_module._Progress.on_episode

    def heard(self, result):  # the task reports an episode once its save is complete
        on_episode(self, result)
        if result.kept:
            first_saved.set()

    monkeypatch.setattr(collect_module._Progress, "on_episode", heard)

    def ctrl_c():
        if first_saved.wait(timeout=900):
            os.kill(os.getpid(), signal.SIGINT)

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal, even in a background job
    try:
        watcher = threading.Thread(target=ctrl_c, daemon=True)
        watcher.start()
        status = main(argv)
        watcher.join(timeout=1)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert first_saved.is_set(), "the driver never heard of a saved episode"
    if status == 0:  # nothing was left when the cancel reached the task: the run is done, and says so
        assert sorted(json.loads((out / MARKER).read_text())["episodes"]) == list(range(8))
        same_episodes(out, reference, only=range(4))
        pytest.skip("the shard finished before the Ctrl-C's cancel reached it (a loaded machine): nothing to resume")
    assert status == 130
    assert "interrupted: every finished episode is saved" in capsys.readouterr().out
    marker = json.loads((out / MARKER).read_text())
    assert 1 <= len(marker["episodes"]) < 8 and set(marker["episodes"]) == set(marker["tried"])

    summary = collect(CollectConfig(out=str(out), episodes=8, boxes_per_episode=2, cameras=(), shard_size=8,
                                    executor=ExecutorConfig("ray", 1), resume=True), **QUIET)
    assert not summary.errors and summary.dataset_episodes == 8
    assert sorted(json.loads((out / MARKER).read_text())["episodes"]) == list(range(8))
    same_episodes(out, reference, only=range(4))  # the reference holds the first 4
