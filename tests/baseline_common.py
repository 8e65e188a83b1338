"""What the learned baselines' test modules share: the shipped policies, a subprocess runner, the pipeline's stages
run in the test's process, scores rows."""

import os
import shlex
import subprocess
import sys
import time
from pathlib import Path

from helpers import console_script

from colorsort.errors import StageError

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
SHIPPED = {name: REPO / "baselines" / name
           for name in ("act-state", "act-camera", "act-camera-snapshot", "act-camera-tracking",
                        "act-camera-tracking-fast-dagger", "act-camera-tracking-dagger",
                        "act-camera-tracking-dip-dagger", "diffusion-camera-snapshot")}


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


def run_in_process(cmd: list[str], log: Path, append: bool = False) -> float:
    """``stages.run`` without a new interpreter (seconds of imports each: LeRobot's alone take 10 to 15 s here): the
    same arguments to the same console script's entry point (``helpers.console_script``), its output to ``log``."""
    print("$ " + shlex.join(cmd), flush=True)
    log.parent.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    done = console_script(Path(cmd[0]).name, cmd[1:], Path.cwd())
    with log.open("a" if append else "w") as f:
        f.write(done.stdout + done.stderr)
    if done.returncode != 0:
        raise StageError(f"exit code {done.returncode}: {shlex.join(cmd)}\n{log.read_text()[-3000:]}")
    return time.perf_counter() - started
