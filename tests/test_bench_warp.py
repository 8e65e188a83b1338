"""The batched cell's benchmark scripts: bench_warp.py's figures on Warp's CPU device in small, and
bench_warp_scores.py's comparison of batched-cell runs with a baseline's published CPU scores."""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SCRIPT = REPO / "benchmarks" / "bench_warp_scores.py"
NO_FILES = {**os.environ, "COLORSORT_RESULTS": "none"}


@pytest.mark.slow
def test_bench_warp_times_worlds_cameras_and_a_policy_on_both_cells(tmp_path):
    """In small, on Warp's CPU device: control steps of 2 worlds, the snapshot camera of 2, the state policy's 3
    episodes rolling on 2 worlds and 2 on the CPU cell in one process; every figure present and positive."""
    argv = ["--device", "cpu", "--worlds", "2", "--steps", "1", "--render-worlds", "2", "--cameras", "snapshot",
            "--image-size", "32", "--policy", "baselines/act-state", "--policy-worlds", "2", "--policy-episodes", "3",
            "--episode-length", "20", "--cpu-policy-episodes", "2", "--cpu-procs", "1", "--cpu-steps", "10",
            "--json", str(tmp_path / "f.json")]
    out = subprocess.run([sys.executable, str(REPO / "benchmarks" / "bench_warp.py"), *argv], cwd=REPO,
                         capture_output=True, text=True, env=NO_FILES)
    assert out.returncode == 0, out.stderr[-2000:]
    f = json.loads((tmp_path / "f.json").read_text())
    assert f["worlds"]["2"]["control_steps_per_s"] > 0 and f["render"]["2"]["images_per_s"] > 0
    policy = f["policy"]["2"]
    assert policy["episodes"] == 3 and policy["control_steps"] > 20  # the third episode after one of the first two
    assert [e["steps"] for e in policy["per_episode"]] == [20, 20, 20]  # each cut at its own 20 steps
    assert f["cpu_policy"]["episodes"] == 2 and f["cpu_policy"]["episodes_per_min"] > 0
    assert "times that." in out.stdout


def cpu_row(policy: str, variant: str) -> dict:
    rows = json.loads((REPO / policy / "scores.json").read_text())["rows"]
    return next(r for r in rows if r["seed"] == rows[0]["seed"] and r["variant"] == variant)


def as_run(row: dict, policy: str, episodes: list[dict]) -> dict:
    """A batched run's record (``bench_warp_scores.evaluate``'s) with these episodes."""
    from colorsort.benchmark.episode_result import EpisodeResult
    from colorsort.benchmark.metrics import aggregate

    r = aggregate(policy, row["variant"], [EpisodeResult(**{**e, "sorted_times": []}) for e in episodes])
    return {"policy": policy, "variant": row["variant"], "device": "cpu", "envs": 4, "episodes": r.episodes,
            "successes": r.successes, "success_ci95": list(r.success_ci95), "correct": r.correct,
            "misplaced": r.misplaced, "dropped": r.dropped, "seconds": 1.0, "control_steps": 10,
            "per_episode": episodes}


def test_merged_runs_are_held_to_the_shipped_seeds_cpu_interval_episode_by_episode(tmp_path):
    """The CPU cell's own episodes pass as a batched run: inside its interval, every episode the same. With every
    episode failed instead, the rate falls outside and no episode ends the same way."""
    policy = "baselines/act-state"
    row = cpu_row(policy, "default")  # the shipped seed's: 50 of 50
    same = as_run(row, policy, row["per_episode"])
    failed = copy.deepcopy(row["per_episode"])
    for e in failed:
        e.update(success=False, ended="failed", misplaced=1)
        e["boxes"][0]["outcome"] = "misplaced"
    worse = as_run(row, policy, failed)
    (tmp_path / "runs.json").write_text(json.dumps({"gpu": "Warp's CPU device", "runs": [same, worse]}))
    out = subprocess.run([sys.executable, str(SCRIPT), "--merge", str(tmp_path / "runs.json")], cwd=REPO,
                         capture_output=True, text=True, env=NO_FILES)
    assert out.returncode == 0, out.stderr
    lines = [line for line in out.stdout.splitlines() if line.startswith("| `act-state`")]
    assert len(lines) == 2
    assert "| 100% (93-100%), 50 | 100.0% (92.9-100.0%), 50 | yes | 50 / 50 of 50 |" in lines[0]
    assert "| **no** | 0 / 0 of 50 |" in lines[1]
    assert "Inside the CPU cell's interval: 1 of 2" in out.stdout
