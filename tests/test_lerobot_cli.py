"""LeRobot as its users run it: the docs' lerobot-train and lerobot-eval commands, verbatim, on ColorSort.

The commands are read from docs/benchmark.md and docs/data.md, the pages that show them, so a test
that passes means the documented command works. README's lerobot-eval and lerobot-dataset-viz run as processes of
their own, as a user runs them (the evaluation finds ColorSort's env type by LeRobot's plugin discovery in a fresh
interpreter; Rerun finishes its file at the process's exit); every other LeRobot command, README's lerobot-train
included, by its console script's entry point in the test's process (``helpers.console_script``: the same argv and
code without 10 to 15 s of LeRobot's imports each).

Only what the docs say may change is changed: the
training length, batch and data-loading processes (``--steps``, ``--batch_size``, ``--num_workers=0``: each
spawned loader imports torch and LeRobot again), the evaluation's episode count and batch size (and
``use_async_envs`` for the synchronous runs). Everything else is LeRobot's defaults.
"""

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import console_script

from colorsort.benchmark.evaluate import evaluate

pytestmark = pytest.mark.slow  # LeRobot's CLIs

DOCS = Path(__file__).resolve().parents[1] / "docs"
PAGES = (DOCS / "benchmark.md", DOCS / "data.md", DOCS / "baselines.md")  # the pages that show LeRobot's commands
BIN = Path(sys.executable).parent


def documented_command(program: str, containing: str = "") -> list[str]:
    """The docs' first shell command that runs ``program`` (and holds ``containing``), continuation lines
    joined, as argv."""
    text = "\n".join(page.read_text() for page in PAGES).replace("\\\n", " ")
    line = next(line for line in text.splitlines() if re.search(rf"(^|\s){program}\s", line) and containing in line)
    argv = shlex.split(line)
    env_assignments = [a for a in argv[: argv.index(program)] if "=" in a]
    wanted = ["HF_HUB_OFFLINE=1"] if program.startswith("lerobot") else []
    assert env_assignments == wanted, f"the docs' {program} command sets {env_assignments}"
    return argv[argv.index(program):]


def replace_flag(argv: list[str], flag: str, value: str) -> list[str]:
    """``argv`` with ``flag=...`` (LeRobot's form) or ``flag ...`` (argparse's) set to ``value``."""
    if flag in argv:
        k = argv.index(flag)
        return argv[: k + 1] + [value] + argv[k + 2:]
    assert any(a.startswith(f"{flag}=") for a in argv), f"the docs' command has no {flag}"
    return [f"{flag}={value}" if a.startswith(f"{flag}=") else a for a in argv]


def run(argv: list[str], cwd: Path, timeout: float) -> subprocess.CompletedProcess:
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    argv = [str(BIN / argv[0])] + argv[1:]
    return subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def readme_checkpoint(tmp_path_factory):
    """The docs' lerobot-train command, 2 steps, on a one-episode dataset recorded with colorsort-collect's defaults
    (one box: the features are the defaults', the episode shorter)."""
    from colorsort.data.collect import CollectConfig, collect

    work = tmp_path_factory.mktemp("readme")
    collect(CollectConfig(out=str(work / "datasets" / "colorsort"), episodes=1, boxes_per_episode=1), progress=False,
            log=lambda _: None)
    argv = replace_flag(replace_flag(documented_command("lerobot-train"), "--steps", "2"), "--batch_size", "2")
    train = console_script(argv[0], argv[1:] + ["--num_workers=0"], work)
    assert train.returncode == 0, train.stderr[-3000:]
    assert (work / "outputs/train/act/checkpoints/last/pretrained_model/model.safetensors").is_file()
    return work


def newest_eval_info(work: Path) -> dict:
    """The ``overall`` metrics of the last lerobot-eval run (outputs/eval/<date>/<time>_colorsort_<policy>/)."""
    newest = max((work / "outputs" / "eval").rglob("eval_info.json"), key=lambda p: p.stat().st_mtime)
    return json.loads(newest.read_text())["overall"]


def test_readme_lerobot_eval_command_runs_as_written(readme_checkpoint):
    """Two episodes of 30 steps in LeRobot's default asynchronous vector env, each filmed (the synchronous one,
    with the pre-0.6 --env.discover_packages_path, runs in the recorded evaluation's test). A fresh interpreter:
    nothing imports ColorSort but LeRobot 0.6's discovery of installed ``lerobot_env_*`` plugins, which finds the
    env type (no --env.discover_packages_path)."""
    batch_size = 2
    argv = replace_flag(documented_command("lerobot-eval"), "--eval.n_episodes", str(batch_size))
    argv = replace_flag(argv, "--eval.batch_size", str(batch_size)) + ["--env.episode_length=30"]
    done = run(argv, readme_checkpoint, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    summary = newest_eval_info(readme_checkpoint)
    assert summary["n_episodes"] == batch_size and 0.0 <= summary["pc_success"] <= 100.0
    videos = [readme_checkpoint / p for p in summary["video_paths"]]  # relative to the working directory
    assert videos and all(p.stat().st_size > 1000 for p in videos)  # LeRobot renders episodes by default


def test_a_state_only_env_config_has_no_visual_features():
    from lerobot.utils.constants import OBS_ENV_STATE, OBS_STATE

    from colorsort.envs.lerobot_env import ColorSortEnv

    cfg = ColorSortEnv(cameras="none", task="ColorSort-RobotsPanda-v0")
    assert set(cfg.features_map.values()) == {"action", OBS_STATE, OBS_ENV_STATE}
    assert cfg.features["action"].shape == (9,) and cfg.gym_kwargs["cameras"] == ()  # the Panda has 7 joints


def test_an_unknown_task_names_the_valid_ones():
    from colorsort.envs.lerobot_env import ColorSortEnv

    with pytest.raises(ValueError, match="Valid tasks: .*ColorSort-Jitter-v0"):
        ColorSortEnv(task="ColorSort-Hard-v0")


@pytest.mark.parametrize("flag, named", [
    ("--env.shift=bogus:1", "Valid shifts: ['action-delay'"),
    ("--env.shift=camera-pose:5", "is not one of [0, 1, 2, 3, 'train']"),
    ("--env.task=ColorSort-Hard-v0", "Valid tasks: ['ColorSort-Default-v0'"),
    ("--env.backend=gpu", "valid backends: ['cpu', 'warp']")])
def test_a_bad_env_flag_ends_lerobots_error_with_the_valid_values(flag, named, tmp_path):
    """``lerobot-eval --env.type=colorsort`` with a bad task, backend or shift: LeRobot's parser (draccus) stops
    with one line naming the field and the valid values, no traceback, nothing evaluated."""
    argv = ["lerobot-eval", "--env.type=colorsort", flag, "--policy.path=baselines/act-state",
            "--policy.device=cpu", f"--output_dir={tmp_path / 'eval'}"]
    done = console_script("lerobot-eval", argv[1:], tmp_path)
    lines = (done.stdout + done.stderr).strip().splitlines()
    assert done.returncode != 0 and not (tmp_path / "eval").exists()
    assert lines[-1].startswith(f"error: `env.{flag[6:].split('=')[0]}`: ") and named in lines[-1]
    assert not any("Traceback" in line for line in lines)


def tiny_act(dataset_root, out_dir):
    """A small randomly initialised ACT policy built from a recorded dataset's features, saved as a checkpoint."""
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.act.modeling_act import ACTPolicy
    from lerobot.policies.factory import make_pre_post_processors
    from lerobot.utils.feature_utils import dataset_to_policy_features

    meta = LeRobotDatasetMetadata("local/colorsort", root=dataset_root)
    features = dataset_to_policy_features(meta.features)
    outputs = {k: f for k, f in features.items() if k == "action"}
    inputs = {k: f for k, f in features.items() if k != "action"}
    config = ACTConfig(input_features=inputs, output_features=outputs, device="cpu", pretrained_backbone_weights=None,
                       dim_model=32, n_heads=2, dim_feedforward=64, n_encoder_layers=1, n_decoder_layers=1,
                       use_vae=False, chunk_size=5, n_action_steps=5)
    policy = ACTPolicy(config)
    pre, post = make_pre_post_processors(config, dataset_stats=meta.stats)
    policy.save_pretrained(out_dir)
    pre.save_pretrained(out_dir)
    post.save_pretrained(out_dir)
    return out_dir


def test_a_lerobot_policy_runs_an_episode_through_lerobots_env_config(tiny_dataset, tmp_path):
    import torch
    from lerobot.envs.factory import make_env, make_env_pre_post_processors
    from lerobot.scripts.lerobot_eval import rollout

    from colorsort.benchmark.policies import LeRobotPolicy
    from colorsort.envs.lerobot_env import ColorSortEnv

    checkpoint = tiny_act(tiny_dataset, tmp_path / "act")
    loaded = LeRobotPolicy(checkpoint)  # what colorsort-eval --policy PATH loads
    env_cfg = ColorSortEnv(image_size=64, episode_length=15)
    envs = make_env(env_cfg, n_envs=1)["colorsort"][0]
    env_pre, env_post = make_env_pre_post_processors(env_cfg, loaded.policy.config)
    with torch.no_grad():
        out = rollout(envs, loaded.policy, env_pre, env_post, loaded.preprocessor, loaded.postprocessor, seeds=[3])
    envs.close()
    assert tuple(out["action"].shape) == (1, 15, 8)  # one episode, truncated at 15 steps
    assert bool(out["done"][0, -1]) and torch.isfinite(out["action"]).all()

    report = evaluate(str(checkpoint), "default", episodes=1, image_size=(64, 64), progress=False, episode_length=10)
    assert report.episodes == 1 and report.success_rate == 0.0 and report.per_episode[0]["steps"] == 10


def test_documented_command_makes_a_state_only_copy_of_a_dataset_with_cameras(tiny_dataset, tmp_path):
    """The docs' lerobot-edit-dataset command, verbatim: the camera features go, states and actions stay."""
    import shutil

    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    shutil.copytree(tiny_dataset, tmp_path / "datasets" / "colorsort")
    argv = documented_command("lerobot-edit-dataset")
    done = console_script(argv[0], argv[1:], tmp_path)
    assert done.returncode == 0, (done.stdout + done.stderr)[-3000:]
    original = LeRobotDataset("local/colorsort", root=tmp_path / "datasets" / "colorsort", video_backend="pyav")
    state_only = LeRobotDataset("local/colorsort-state", root=tmp_path / "datasets" / "colorsort-state")
    assert original.meta.video_keys and state_only.meta.video_keys == []
    assert state_only.num_episodes == original.num_episodes and state_only.num_frames == original.num_frames
    last = len(original) - 1
    for key in ("observation.state", "observation.environment_state", "action"):
        assert np.array_equal(state_only[last][key].numpy(), original[last][key].numpy())


def test_lerobot_eval_records_rollouts_as_datasets_that_colorsort_replay_explains(readme_checkpoint):
    """The docs' recorded lerobot-eval, 2 episodes of 30 steps in LeRobot's synchronous vector env (found through
    --env.discover_packages_path): a LeRobot dataset per env of the batch."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    argv = replace_flag(documented_command("lerobot-eval", "--eval.recording=true"), "--eval.n_episodes", "2")
    argv.insert(1, "--env.discover_packages_path=colorsort")  # the pre-0.6 way keeps working
    done = console_script(argv[0], argv[1:] + ["--env.episode_length=30", "--eval.use_async_envs=false"],
                          readme_checkpoint)
    assert done.returncode == 0, (done.stdout + done.stderr)[-3000:]
    root = readme_checkpoint / "outputs/eval/recorded/recordings/colorsort_0"
    for i in range(2):
        ds = LeRobotDataset(f"eval_recording_env_{i}", root=root / f"env_{i}", video_backend="pyav")
        assert ds.num_episodes == 1 and ds.num_frames == 30
        last = ds[len(ds) - 1]
        assert tuple(last["observation.images.scene"].shape) == (3, 128, 128)
        assert tuple(last["agent_pos"].shape) == (23,) and tuple(last["action"].shape) == (8,)
        assert bool(last["next.done"]) and not bool(last["next.success"])
    replay = run(["colorsort-replay", str(root / "env_0")], readme_checkpoint, timeout=300)
    assert replay.returncode == 2 and "evaluation recording" in replay.stderr and "lerobot-dataset-viz" in replay.stderr
    assert len(replay.stderr.strip().splitlines()) == 1  # one line, no traceback


def test_lerobot_dataset_viz_saves_an_rrd_of_a_colorsort_dataset(tiny_dataset, tmp_path):
    """The docs' lerobot-dataset-viz command (the viz extra) on a small dataset: Rerun reads the .rrd back."""
    from rerun.experimental import RrdReader

    argv = replace_flag(documented_command("lerobot-dataset-viz"), "--root", str(tiny_dataset))
    argv = replace_flag(argv, "--repo-id", "local/colorsort")
    done = run(argv, tmp_path, timeout=300)  # its own process: Rerun writes the file's footer as the process ends
    assert done.returncode == 0, done.stderr[-3000:]
    rrd = tmp_path / "outputs" / "viz" / "local_colorsort_episode_0.rrd"
    assert rrd.stat().st_size > 10_000
    paths = set(RrdReader(str(rrd)).store().schema().entity_paths())
    assert {"/observation.images.scene", "/observation.images.wrist", "/action", "/state"} <= paths


def test_lerobot_trains_a_diffusion_policy_on_colorsort_that_colorsort_eval_runs(tmp_path, monkeypatch):
    """The docs' diffusion commands (the diffusion extra) in small: 2 demos, 2 updates, one short episode
    (ColorSort's own two commands parsed by their own main in this process, LeRobot's in its own)."""
    from colorsort.cli.collect import main as collect_main
    from colorsort.cli.eval import main as eval_main

    monkeypatch.chdir(tmp_path)
    collect = replace_flag(documented_command("colorsort-collect", "--cameras none"), "--episodes", "2")
    assert collect_main(replace_flag(collect, "--boxes-per-episode", "1")[1:]) == 0
    train = replace_flag(documented_command("lerobot-train", "--policy.type=diffusion"), "--steps", "2")
    done = console_script(train[0], replace_flag(train, "--batch_size", "2")[1:] + ["--num_workers=0"], tmp_path)
    assert done.returncode == 0, (done.stdout + done.stderr)[-3000:]
    config = json.loads((tmp_path / "outputs/train/diffusion-state/checkpoints/last/pretrained_model/config.json")
                        .read_text())
    assert config["type"] == "diffusion" and config["down_dims"] == [128, 256]
    assert "observation.environment_state" in config["input_features"]
    evaluate_cmd = documented_command("colorsort-eval", "diffusion-state")
    assert eval_main(replace_flag(evaluate_cmd, "--episodes", "1")[1:] + ["--episode-length", "30", "--json",
                                                                          "eval.json"]) == 0
    result = json.loads((tmp_path / "eval.json").read_text())
    assert result["episodes"] == 1 and result["per_episode"][0]["steps"] == 30
