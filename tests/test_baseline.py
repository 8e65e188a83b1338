"""The learned baseline: demos/train_baseline.py end to end (tiny), and the shipped checkpoint in both evaluators."""

import json
import os
import subprocess
import sys
from pathlib import Path

import cv2
import pytest

from colorsort.cli.eval import main as eval_main

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
SHIPPED = REPO / "baselines" / "act-state"


def run(argv: list[str], cwd: Path, timeout: float) -> subprocess.CompletedProcess:
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    return subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


def test_the_baseline_script_runs_end_to_end_in_a_tiny_configuration(tmp_path):
    """Two demo counts from two variants (merged with LeRobot's aggregate_datasets), 2 training steps each,
    one evaluation episode per variant; then the same command again reuses every finished stage."""
    out, ship = tmp_path / "baseline", tmp_path / "shipped"
    argv = [sys.executable, str(REPO / "demos" / "train_baseline.py"), "--demos", "2,3",
            "--train-variants", "default,distractors", "--steps", "2", "--small-steps", "2", "--batch-size", "2",
            "--eval-variants", "default,jitter", "--eval-episodes", "1", "--other-episodes", "1",
            "--episode-length", "10", "--workers", "1", "--envs", "1", "--out", str(out)]
    first = run(argv + ["--ship", str(ship)], tmp_path, timeout=900)
    assert first.returncode == 0, first.stdout[-3000:] + first.stderr[-3000:]

    results = json.loads((out / "results.json").read_text())["results"]
    assert [(r["demos"], r["variant"], r["steps"]) for r in results] == [(2, "default", 2), (3, "default", 2),
                                                                          (3, "jitter", 2)]
    assert all(r["episodes"] == 1 and r["success_rate"] == 0.0 for r in results)  # 10 steps sort nothing
    assert "| default | ACT, state | 3 | 2 steps" in first.stdout
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    merged = LeRobotDataset("local/colorsort-baseline", root=out / "data" / "demos-3")
    assert merged.num_episodes == 3 and merged.meta.video_keys == []
    assert len(merged.meta.tasks) >= 1
    image = cv2.imread(str(out / "success_vs_demos.png"))
    assert image is not None and image.shape[0] > 200 and image.shape[1] > 300

    shipped = {p.name for p in ship.iterdir()}
    assert {"config.json", "model.safetensors", "README.md", "success_vs_demos.png"} <= shipped
    assert any(name.startswith("policy_preprocessor") for name in shipped)
    readme = (ship / "README.md").read_text()
    assert "train_baseline.py" in readme and "commit" in readme and "| jitter | ACT, state | 3 |" in readme
    assert eval_main(["--policy", str(ship), "--variant", "default", "--episodes", "1", "--episode-length", "5"]) == 0

    again = run(argv, tmp_path, timeout=600)
    assert again.returncode == 0, again.stderr[-3000:]
    assert again.stdout.count("reusing") == 2 + 2 + 3 and "lerobot-train" not in again.stdout
    assert run(argv + ["--ship", str(ship)], tmp_path, timeout=600).returncode == 2  # never replaces a shipped policy


def test_bad_baseline_settings_name_the_valid_choices(tmp_path):
    script = str(REPO / "demos" / "train_baseline.py")
    bad = run([sys.executable, script, "--train-variants", "default,nope", "--out", str(tmp_path)], tmp_path, 120)
    assert bad.returncode == 2 and "Valid variants" in bad.stderr
    bad = run([sys.executable, script, "--demos", "50,20", "--out", str(tmp_path)], tmp_path, 120)
    assert bad.returncode == 2 and "increasing" in bad.stderr


@pytest.mark.skipif(not SHIPPED.is_dir(), reason="no baseline shipped yet")
def test_the_shipped_baseline_sorts_through_colorsort_eval(tmp_path, capsys):
    """README's command for the shipped policy, on the first default seed: the cameras come from the checkpoint."""
    report = tmp_path / "eval.json"
    assert eval_main(["--policy", str(SHIPPED), "--variant", "default", "--episodes", "1", "--json", str(report)]) == 0
    result = json.loads(report.read_text())
    assert result["correct"] >= 1 and result["dropped"] == 0  # it picks and places: not an untrained policy


@pytest.mark.skipif(not SHIPPED.is_dir(), reason="no baseline shipped yet")
def test_the_shipped_baseline_runs_in_lerobot_eval(tmp_path):
    """README's lerobot-eval command for the shipped policy, one episode."""
    result = run([str(BIN / "lerobot-eval"), "--env.type=colorsort", "--env.task=ColorSort-Default-v0",
                  "--env.cameras=none", f"--policy.path={SHIPPED}", "--policy.device=cpu",
                  "--eval.n_episodes=1", "--eval.batch_size=1", f"--output_dir={tmp_path / 'eval'}"],
                 tmp_path, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    overall = json.loads((tmp_path / "eval" / "eval_info.json").read_text())["overall"]
    assert overall["n_episodes"] == 1 and 0 <= overall["pc_success"] <= 100


def test_the_vision_recipe_runs_in_small_on_the_cpu(tmp_path):
    """README's GPU recipe with the device set to the CPU and everything tiny: the policy takes the camera and
    not the simulator's box state, and colorsort-eval renders what it was trained on."""
    out = tmp_path / "vision"
    result = run([sys.executable, str(REPO / "demos" / "train_baseline.py"), "--cameras", "wrist", "--image-size", "32",
                  "--device", "cpu", "--demos", "1", "--train-variants", "default", "--steps", "2", "--batch-size", "2",
                  "--eval-variants", "default", "--eval-episodes", "1", "--episode-length", "5", "--workers", "1",
                  "--envs", "1", "--out", str(out)], tmp_path, timeout=900)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    info = json.loads((out / "data" / "demos-1" / "meta" / "info.json").read_text())
    assert "observation.images.wrist" in info["features"] and "observation.environment_state" not in info["features"]
    config = json.loads((out / "train" / "demos-1-2steps" / "checkpoints" / "last" / "pretrained_model" / "config.json").read_text())
    assert set(config["input_features"]) == {"observation.state", "observation.images.wrist"}
    assert config["pretrained_backbone_weights"] is None and config["dim_model"] == 512
    assert "| default | ACT, wrist | 1 | 2 steps" in result.stdout
