"""Cells stepped together (``colorsort-eval --batch-size N``, ``benchmark/lockstep.py``) and Ctrl-C that keeps
every finished episode (the journal beside ``--json``, ``--resume``)."""

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from helpers import exit_status

from colorsort.benchmark.episode_result import EpisodeResult
from colorsort.benchmark.lockstep import EpisodePlan, run_rolling, run_waves
from colorsort.benchmark.sweep_journal import journal_path
from colorsort.cli.eval import main as eval_main

ROOT = Path(__file__).resolve().parents[1]


def per_episode(path: Path) -> list[dict]:
    report = json.loads(path.read_text())
    return report["per_episode"]


@pytest.mark.slow
def test_batch_sizes_1_2_and_5_give_the_expert_the_same_episodes_and_json(tmp_path):
    """The expert has no forward to share (its episodes run on one env whatever the batch size): each seed's
    episode is exactly the same at any batch size, and so is the JSON (but for the batch size it names)."""
    runs = {}
    for n in (1, 2, 5):
        out = tmp_path / f"b{n}.json"
        assert exit_status(eval_main, ["--policy", "expert", "--variant", "default", "--episodes", "5",
                                       "--episode-length", "200", "--batch-size", str(n), "--json", str(out)]) == 0
        runs[n] = json.loads(out.read_text())
        assert not journal_path(out).exists()  # the JSON is written: its journal has served
    assert runs[1]["per_episode"] == runs[2]["per_episode"] == runs[5]["per_episode"]
    assert sum(e["correct"] for e in runs[1]["per_episode"]) >= 5  # boxes were sorted, not idle episodes compared
    shape = {n: {k: v for k, v in r.items() if k != "batch_size"} for n, r in runs.items()}
    assert shape[1] == shape[2] == shape[5] and [r["batch_size"] for r in runs.values()] == [1, 2, 5]


@pytest.mark.slow
@pytest.mark.parametrize(("policy", "sizes"), [("act-state", (1, 2, 5)), ("diffusion-camera-snapshot", (1, 3))])
def test_batch_sizes_give_a_checkpoint_the_same_outcomes(tmp_path, policy, sizes):
    """A LeRobot checkpoint acts on 1, 2 or 5 cells in one forward: the same outcome, steps and boxes for each
    seed (a batch of another size may round its last bits otherwise). Diffusion Policy draws each world's noise
    from its episode's seed, as the episode alone would."""
    outcomes = {}
    for n in sizes:
        out = tmp_path / f"b{n}.json"
        assert exit_status(eval_main, ["--policy", str(ROOT / "baselines" / policy), "--variant", "default",
                                       "--episodes", "3", "--episode-length", "200", "--batch-size", str(n),
                                       "--json", str(out)]) == 0
        outcomes[n] = [(e["seed"], e["ended"], e["steps"], e["correct"], [b["bin"] for b in e["boxes"]])
                       for e in per_episode(out)]
    assert all(outcomes[n] == outcomes[sizes[0]] for n in sizes)
    assert sum(o[3] for o in outcomes[sizes[0]]) >= 3


class FakeCells:
    """Cells whose episode ``seed`` ends after ``seed`` steps; records when each world starts what."""

    def __init__(self, worlds: int):
        self.worlds = worlds
        self.length = np.zeros(worlds, int)
        self.steps = np.zeros(worlds, int)
        self.seeds = np.zeros(worlds, int)
        self.started: list[tuple[int, int, int]] = []  # (control step, world, seed)
        self.t = 0

    def reset(self, episodes, worlds):
        for w, e in zip(worlds, episodes, strict=True):
            self.length[w], self.steps[w], self.seeds[w] = e.seed, 0, e.seed
            self.started.append((self.t, int(w), e.seed))
        return None

    def step(self, actions, active):
        self.t += 1
        self.steps[active] += 1
        return None

    def ended(self):
        return self.steps >= self.length

    def results(self, worlds, steps):
        assert (self.steps[worlds] == steps).all()  # a world's episode counts its own steps only
        return [EpisodeResult(int(self.seeds[w]), True, "success", int(n), 0, 0, 0, 0, 0, 0.0, [], [])
                for w, n in zip(worlds, steps, strict=True)]


class NullPolicy:
    name, restart_period = "null", 4

    def reset(self, seed):
        pass

    def begin(self, worlds, episodes):
        pass

    def act(self, obs, task, active):
        return np.zeros((len(active), 1))


def test_rolling_starts_the_next_episode_in_a_freed_world_at_a_restart_point_and_waves_wait():
    lengths = [5, 13, 7, 6, 9]
    cells = FakeCells(2)
    results, _ = run_rolling(cells, NullPolicy(), [EpisodePlan(s) for s in lengths], 100, 4, "t", progress=False)
    assert [r.seed for r in results] == lengths and [r.steps for r in results] == lengths
    # world 0 ends its 5 at step 5, takes 7 at step 8 (the next restart point), ends at 15, takes 6 at 16 ...;
    # world 1 runs its 13 undisturbed, then takes 9 at the restart point 16
    assert cells.started == [(0, 0, 5), (0, 1, 13), (8, 0, 7), (16, 0, 6), (16, 1, 9)]
    waves = FakeCells(2)
    results, _ = run_waves(waves, NullPolicy(), [EpisodePlan(s) for s in lengths], 100, "t", progress=False)
    assert [r.steps for r in results] == lengths
    assert waves.started == [(0, 0, 5), (0, 1, 13), (13, 0, 7), (13, 1, 6), (20, 0, 9)]  # each wave waits its longest
    stopped = FakeCells(2)
    calls = iter(range(1000))
    results, _ = run_rolling(stopped, NullPolicy(), [EpisodePlan(s) for s in lengths], 100, 4, "t", progress=False,
                             stop=lambda: next(calls) >= 3)  # a stop at step 3: the worlds finish, nothing starts
    assert [r.seed if r else None for r in results] == [5, 13, None, None, None]


def interrupt_when_journaled(argv: list[str], journal: Path, cwd: Path, timeout: float = 240.0):
    """Run ``colorsort-eval argv`` in a new process group, SIGINT the group once ``journal`` holds an episode;
    (exit status, stderr, seconds from the SIGINT to the exit)."""
    exe = Path(sys.executable).with_name("colorsort-eval")
    process = subprocess.Popen([str(exe), *argv], cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               start_new_session=True, env={**os.environ, "COLORSORT_RESULTS": "none"})
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        if journal.exists() and len(journal.read_text().splitlines()) >= 2:  # the header and one episode
            break
        time.sleep(0.05)
    sent = time.monotonic()
    os.killpg(process.pid, signal.SIGINT)
    _, err = process.communicate(timeout=120)
    return process.returncode, err, time.monotonic() - sent


@pytest.mark.slow
@pytest.mark.parametrize("extra", [[], ["--batch-size", "2"], ["--sweep", "--sweep-shifts", "image-noise",
                                                                  "--levels", "2"]],
                         ids=["plain", "batched", "sweep"])
def test_ctrl_c_keeps_every_finished_episode_and_resume_completes_the_run(tmp_path, extra):
    """Ctrl-C (SIGINT to the process group, as a terminal sends it) at --envs 1: exit 130 within seconds, one
    line, the journal holds every finished episode, and --resume gives what an uninterrupted run gives."""
    argv = ["--policy", "expert", "--variant", "default", "--episodes", "6", "--episode-length", "80", *extra]
    whole, out = tmp_path / "whole.json", tmp_path / "out.json"
    assert exit_status(eval_main, [*argv, "--json", str(whole)]) == 0
    journal = journal_path(out)
    status, err, after = interrupt_when_journaled([*argv, "--json", str(out)], journal, tmp_path)
    lines = [line for line in re.split(r"[\r\n]+", err) if line and not re.search(r"\d+/\d+ \[", line)]  # tqdm's bar
    assert status == 130 and not out.exists(), err
    assert len(lines) == 1 and "Traceback" not in err, err
    found = re.fullmatch(r"colorsort-eval: interrupted: (\d+) of (\d+) episodes kept in (.+); --resume continues",
                         lines[0])
    assert found and Path(found[3]) == journal, lines[0]
    kept, total = int(found[1]), int(found[2])
    assert kept == len(journal.read_text().splitlines()) - 1 and 1 <= kept < total
    assert after < 30  # within about one episode (80 steps), not the rest of the run
    assert exit_status(eval_main, [*argv, "--json", str(out), "--resume"]) == 0 and not journal.exists()
    done, reference = json.loads(out.read_text()), json.loads(whole.read_text())
    if "--sweep" in extra:
        assert done["rows"] == reference["rows"] and done["resumed_episodes"] == kept
        assert [r["per_episode"] for r in done["reports"]] == [r["per_episode"] for r in reference["reports"]]
    else:
        assert done["per_episode"] == reference["per_episode"]


def test_resume_needs_json_and_batch_size_and_precision_are_checked(capsys):
    base = ["--policy", "expert", "--variant", "default", "--episodes", "1"]
    assert exit_status(eval_main, [*base, "--resume"]) == 2 and "give --json" in capsys.readouterr().err
    assert exit_status(eval_main, [*base, "--batch-size", "0"]) == 2 and "1 to 1024" in capsys.readouterr().err
    assert exit_status(eval_main, [*base, "--precision", "fp8"]) == 2
    assert "['float32', 'bfloat16']" in capsys.readouterr().err
    assert exit_status(eval_main, [*base, "--precision", "bfloat16", "--batch-size", "2"]) == 2
    assert "a learned policy's batched forward" in capsys.readouterr().err


@pytest.mark.slow
def test_a_batched_sweep_and_a_batched_report_give_what_batch_size_1_gives(tmp_path):
    """--batch-size reaches sweeps (each cell switches its own shifts) and filmed reports (each cell films its own
    episodes): the same rows and outcomes as one env at a time, a video per filmed episode."""
    policy = str(ROOT / "baselines/act-state")
    sweep = ["--policy", policy, "--variant", "default", "--sweep", "--sweep-shifts", "image-noise,box-offset",
             "--levels", "2", "--episodes", "3", "--episode-length", "120"]
    rows = {}
    for n in (1, 3):
        out = tmp_path / f"sweep{n}.json"
        assert exit_status(eval_main, [*sweep, "--batch-size", str(n), "--json", str(out)]) == 0
        done = json.loads(out.read_text())
        rows[n] = [(r["shift"], r["level"], r["success"], r["misplaced"], r["dropped"]) for r in done["rows"]]
        assert done["batch_size"] == n and done["precision"] == "float32"
    assert rows[1] == rows[3] and len(rows[1]) == 3
    report = tmp_path / "report"
    assert exit_status(eval_main, ["--policy", policy, "--variant", "default", "--episodes", "2", "--episode-length",
                                   "60", "--batch-size", "2", "--report", str(report), "--videos", "2"]) == 0
    videos = sorted((report / "videos").glob("*.mp4"))
    assert len(videos) == 2 and all(v.stat().st_size > 1000 for v in videos)
