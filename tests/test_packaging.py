"""The package installs without -e: the wheel carries the MJCF assets, and they load from it."""

import os
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ASSETS = [
    "colorsort/assets/irb140/robot.xml",
    "colorsort/assets/irb140/README.md",
    "colorsort/assets/suction_gripper/suction_gripper.xml",
    "colorsort/assets/suction_gripper/README.md",
    "colorsort/assets/arena/conveyor_arena.xml",
    "colorsort/assets/controllers/joint_position_absolute.json",
]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    # Build from a copy: setuptools writes build/ and *.egg-info next to the sources.
    src = tmp_path_factory.mktemp("src") / "colorsort"
    skip = shutil.ignore_patterns(".venv", ".git", "build", "*.egg-info", "outputs", "datasets")
    shutil.copytree(ROOT, src, ignore=skip)
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(out), str(src)],
        check=True, env={**os.environ, "PIP_NO_INDEX": "1"},
    )
    (whl,) = out.glob("colorsort-*.whl")
    return whl


@pytest.mark.slow
def test_wheel_lists_the_mjcf_assets(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    missing = [a for a in ASSETS if a not in names]
    assert not missing, f"missing from {wheel.name}: {missing}"


@pytest.mark.slow
def test_task_builds_from_the_installed_wheel(wheel, tmp_path):
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(target), str(wheel)],
                   check=True, env={**os.environ, "PIP_NO_INDEX": "1"})
    code = (
        "import colorsort, robosuite as suite; "
        "env = suite.make('ColorSort', robots='IRB140', has_offscreen_renderer=False); env.reset(); "
        "print(colorsort.__file__); print(env.sim.model.nbody)"
    )
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True, cwd=tmp_path,
                         env={**os.environ, "PYTHONPATH": str(target)}).stdout.split()
    assert out[0].startswith(str(target))  # imported from the wheel, not the checkout
    assert int(out[1]) > 20


def test_missing_gl_backend_gives_a_clear_message(tmp_path):
    proc = subprocess.run([sys.executable, "-c", "import colorsort"], capture_output=True, text=True, cwd=tmp_path,
                          env={**os.environ, "MUJOCO_GL": "osmesa", "PYOPENGL_PLATFORM": "osmesa"})
    if proc.returncode == 0:
        pytest.skip("this machine has OSMesa: no failing backend to show")
    assert "MUJOCO_GL='osmesa'" in proc.stderr and "MUJOCO_GL=egl" in proc.stderr


def plain_shell() -> dict[str, str]:
    """The environment of a shell with the venv active and nothing else set: no MUJOCO_GL, as make exports."""
    return {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"} | {"COLORSORT_RESULTS": "none"}


@pytest.mark.parametrize(("argv", "printed"), [
    (["benchmarks/bench_env.py", "--seconds", "0.05", "--repeats", "2"], "frames/s"),
    (["benchmarks/bench_eval.py", "--policies", "expert", "--episodes", "2", "--repeats", "1", "--envs", "1",
      "--batch-sizes", "1,2"], "same outcome"),
], ids=["bench_env", "bench_eval"])
def test_a_benchmark_script_runs_from_a_plain_shell(argv, printed):
    """docs/speed.md's commands with no MUJOCO_GL or HF_HUB_OFFLINE set: each script sets what it needs first, and
    what it prints is measured (the env's ratio to raw MuJoCo; the expert's episodes the same at both sizes)."""
    env = {k: v for k, v in plain_shell().items() if k != "HF_HUB_OFFLINE"}
    proc = subprocess.run([sys.executable, *argv], capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert printed in proc.stdout
    if "bench_env" in argv[0]:
        ratio = float(re.search(r"^env / raw +([\d.]+)", proc.stdout, flags=re.M)[1])
        assert 0.05 < ratio < 1.5
    else:
        assert len(re.findall(r" 2/2 +100% ", proc.stdout)) == 2  # every episode the same, and sorted


def test_mujoco_imported_before_colorsort_gets_a_message_naming_the_backend_it_loaded(tmp_path):
    code = "import mujoco, robosuite, colorsort; from colorsort.cell.rendering import check_gl; check_gl()"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path,
                          env=plain_shell() | {"DISPLAY": ""}, timeout=120)
    if proc.returncode == 0:
        pytest.skip("MuJoCo's default backend renders here (a display): nothing to explain")
    assert "MuJoCo loaded its 'glfw' backend before MUJOCO_GL was 'egl'" in proc.stderr
    assert "Import colorsort before mujoco" in proc.stderr


def test_find_python_names_a_312_interpreter_or_says_what_to_install(tmp_path):
    """make's interpreter search: LeRobot 0.6 needs Python >= 3.12."""
    script = ROOT / "tools" / "find-python"
    found = subprocess.run(["sh", str(script)], capture_output=True, text=True,
                           env={**os.environ, "PYTHON": sys.executable})
    assert found.returncode == 0
    version = subprocess.run([found.stdout.strip(), "-c", "import sys; print(sys.version_info[:2] >= (3, 12))"],
                             capture_output=True, text=True).stdout
    assert version.strip() == "True"
    old = tmp_path / "python3"  # a PATH whose only python3 is too old, and no pyenv or uv
    old.write_text("#!/bin/sh\nexit 1\n")
    old.chmod(0o755)
    (tmp_path / "cat").symlink_to(shutil.which("cat"))
    missing = subprocess.run(["/bin/sh", str(script)], capture_output=True, text=True,
                             env={"PATH": str(tmp_path), "PYTHON": ""})
    assert missing.returncode == 1 and missing.stdout == ""
    assert "Python 3.12 or newer" in missing.stderr and "uv python install 3.12" in missing.stderr


def test_a_shipped_models_weights_change_only_with_its_scores():
    """The repository's weight: every commit that changed a shipped policy's weights changed its scores.json too
    (a re-ship with new scores), so no weight file is committed again for nothing. A ship from before baselines
    had a scores.json (the first act-state) has none to change."""
    repo = Path(__file__).resolve().parents[1]
    if not (repo / ".git").exists() or shutil.which("git") is None:
        pytest.skip("not a git checkout")
    for model in sorted((repo / "baselines").glob("*/model.safetensors")):
        rel = model.relative_to(repo)
        commits = subprocess.run(["git", "log", "--format=%H", "--", str(rel)], cwd=repo, capture_output=True,
                                 text=True, check=True).stdout.split()
        scores = rel.with_name("scores.json")
        for commit in commits:
            if subprocess.run(["git", "cat-file", "-e", f"{commit}:{scores}"], cwd=repo).returncode != 0:
                continue
            changed = subprocess.run(["git", "show", "--name-only", "--format=", commit], cwd=repo,
                                     capture_output=True, text=True, check=True).stdout.split()
            assert str(scores) in changed, f"{commit[:7]} changed {rel} but not its scores"
