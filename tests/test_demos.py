"""Every script in demos/ runs as its docstring shows, verbatim, and does what it says."""

from __future__ import annotations

import ast
import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import python_script

REPO = Path(__file__).resolve().parents[1]
DEMOS = sorted((REPO / "demos").glob("*.py"))


def documented(script: Path) -> list[str]:
    """The command a demo's docstring gives first (its first line that starts ``python demos/``)."""
    doc = ast.get_docstring(ast.parse(script.read_text())) or ""
    (line, *_) = [ln.strip() for ln in doc.splitlines() if ln.strip().startswith(f"python demos/{script.name}")]
    return shlex.split(line)


def run_here(script: str, tmp_path: Path) -> subprocess.CompletedProcess:
    """The documented command in this process (``helpers.python_script``: the file run as ``__main__`` with the
    same argv), for the examples that import LeRobot (10 to 15 s of a new interpreter's time)."""
    argv = documented(REPO / "demos" / script)
    result = python_script(REPO / argv[1], argv[2:], tmp_path)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return result


def run(script: str, tmp_path: Path, timeout: float) -> subprocess.CompletedProcess:
    """The documented command as a process of its own."""
    argv = documented(REPO / "demos" / script)
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    result = subprocess.run([sys.executable, str(REPO / argv[1]), *argv[2:]], cwd=tmp_path, env=env,
                            capture_output=True, text=True, timeout=timeout)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return result


def test_demos_holds_only_examples_each_with_its_command():
    assert {p.name for p in DEMOS} == {"collect_demos.py", "robosuite_env.py", "vector_env.py",
                                       "collect_train_evaluate.py"}
    for script in DEMOS:
        assert documented(script)[:2] == ["python", f"demos/{script.name}"]


def test_the_robosuite_example_sorts_its_boxes(tmp_path):
    out = run("robosuite_env.py", tmp_path, timeout=300).stdout
    assert "green box -> green bin" in out and "2 of 2 boxes placed in the bin of their colour" in out


@pytest.mark.slow
def test_the_vector_env_example_steps_async_cells(tmp_path):
    out = run("vector_env.py", tmp_path, timeout=300).stdout
    assert "2 async envs: agent_pos (2, 23), environment_state (2, 13), pixels.sensor (2, 32, 32, 3)" in out
    assert "after 40 steps of random actions" in out


@pytest.mark.slow
def test_the_collect_demos_script_records_a_loadable_dataset(tmp_path):
    run_here("collect_demos.py", tmp_path)
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    dataset = LeRobotDataset("local/colorsort", root=tmp_path / "datasets" / "example", video_backend="pyav")
    assert dataset.num_episodes == 2 and {"observation.images.scene", "observation.images.wrist"} <= set(
        dataset.meta.video_keys)


@pytest.mark.slow
def test_collect_train_evaluate_from_python_scores_a_trained_policy(tmp_path):
    out = run_here("collect_train_evaluate.py", tmp_path).stdout
    assert "collected 1 episodes" in out and "trained 2 updates" in out
    assert "episodes                 1" in out and "seeds                    10000..10000" in out
    assert (tmp_path / "outputs" / "example" / "train" / "checkpoints" / "last" / "pretrained_model"
            / "model.safetensors").is_file()
