"""What the learned baselines' test modules share: the shipped policies, a subprocess runner, scores rows."""

import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
SHIPPED = {name: REPO / "baselines" / name
           for name in ("act-state", "act-camera", "act-camera-snapshot", "act-camera-tracking")}


def run(argv: list[str], cwd: Path, timeout: float) -> subprocess.CompletedProcess:
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    return subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


def baseline(*args: str) -> list[str]:
    return [str(BIN / "colorsort-baseline"), *args]


def score_row(**fields) -> dict:
    """A row of a scores.json as the pipeline writes it (``ScoreRow.to_json``), with ``fields`` set."""
    row = {"demos_tried": 40, "demos": 40, "frames": 4000, "seed": 1000, "steps": 5000, "passes": 10.0,
           "train_minutes": 20.0, "policy": "p", "variant": "default", "episodes": 50, "successes": 0,
           "success_rate": 0.0, "success_ci95": [0.0, 0.1], "correct": 0, "misplaced": 0, "dropped": 0,
           "per_episode": []}
    return {**row, **fields}


def scores(rows: list[dict], recipe: dict | None = None) -> dict:
    return {"recipe": recipe or {"cameras": []}, "command": "cmd", "started": "then", "wall_s": 1.0, "rows": rows}
