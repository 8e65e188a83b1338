"""The benchmark: Gymnasium ids, variants, the evaluation harness, and LeRobot policies on the task."""

import json

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from colorsort.config import BIN_COLORS, COLORS
from colorsort.evaluate import evaluate, main as eval_main, wilson_interval
from colorsort.gym_env import ColorSortGymEnv
from colorsort.variants import DEFAULT_GYM_ID, VARIANTS, get_variant

SMALL = dict(image_size=(32, 32), cameras=("scene", "wrist"))


@pytest.mark.parametrize("gym_id", [DEFAULT_GYM_ID] + [v.gym_id for v in VARIANTS.values()])
def test_every_registered_id_passes_gymnasiums_env_checker(gym_id):
    env = gym.make(gym_id, **SMALL)
    check_env(env.unwrapped, skip_render_check=False)
    obs, info = env.reset(seed=0)
    assert set(obs) == {"pixels", "agent_pos", "environment_state"} and "is_success" in info
    env.close()


def test_list_prints_one_variant_per_line(capsys):
    assert eval_main(["--list"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert [line.split()[0] for line in lines] == list(VARIANTS)


def test_unknown_variant_names_the_valid_ones(capsys):
    with pytest.raises(ValueError, match="Valid variants"):
        get_variant("hard")
    assert eval_main(["--variant", "hard", "--episodes", "1"]) == 2
    assert "Valid variants" in capsys.readouterr().err


def test_expert_sorts_every_box_on_default():
    report = evaluate("expert", "default", episodes=2, progress=False, **SMALL)
    assert report.success_rate == 1.0 and report.correct == 2 * VARIANTS["default"].boxes
    assert report.misplaced == report.dropped == 0
    assert 9.0 < report.boxes_per_minute < 15.0  # a box every 4 s, the first one rides 4 s to the sensor


def test_random_policy_fails_and_seeded_runs_repeat_exactly():
    first = evaluate("random", "default", episodes=3, seed=7, progress=False, **SMALL)
    again = evaluate("random", "default", episodes=3, seed=7, progress=False, **SMALL)
    assert first.success_rate == 0.0
    assert first.per_episode == again.per_episode and first.seeds == [7, 8, 9]


def test_distractors_are_let_through_and_counted():
    report = evaluate("expert", "distractors", episodes=2, progress=False, **SMALL)
    assert report.success_rate == 1.0
    assert report.distractors > 0 and report.distractors_let_through == report.distractors
    assert report.correct + report.distractors_let_through == 2 * VARIANTS["distractors"].boxes


def test_light_randomisation_never_changes_box_or_bin_colours():
    env = ColorSortGymEnv("lighting", **SMALL)
    m = env.env.sim.model
    bin_geoms = [i for i in range(m.ngeom) if "bin" in (m.geom_id2name(i) or "")]
    bins_before = m.geom_rgba[bin_geoms].copy()
    lights = []
    for seed in range(4):
        env.reset(seed=seed)
        lights.append(m.light_diffuse.copy())
        for box in env.env.boxes_in_play():
            assert np.allclose(m.geom_rgba[env.env._box_geom[box.index]], COLORS[box.color])
        assert np.array_equal(m.geom_rgba[bin_geoms], bins_before)
    assert not np.allclose(lights[0], lights[1])  # the lights did change
    env.close()
    assert len(bin_geoms) >= len(BIN_COLORS)


def test_wilson_interval():
    assert wilson_interval(0, 10)[0] == 0.0 and wilson_interval(10, 10)[1] == 1.0
    lo, hi = wilson_interval(5, 10)
    assert lo < 0.5 < hi


def tiny_act(dataset_root, out_dir):
    """A small randomly initialised ACT policy built from a recorded dataset's features, saved as a checkpoint."""
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata
    from lerobot.datasets.utils import dataset_to_policy_features
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.act.modeling_act import ACTPolicy
    from lerobot.policies.factory import make_pre_post_processors

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

    from colorsort.lerobot_env import ColorSortEnv
    from colorsort.policies import LeRobotPolicy

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

    report = evaluate(str(checkpoint), "default", episodes=1, image_size=(64, 64), progress=False, max_episode_steps=10)
    assert report.episodes == 1 and report.success_rate == 0.0 and report.per_episode[0]["steps"] == 10


def test_eval_cli_writes_the_json(tmp_path, capsys):
    path = tmp_path / "eval.json"
    assert eval_main(["--policy", "random", "--episodes", "1", "--image-size", "32", "--json", str(path)]) == 0
    data = json.loads(path.read_text())
    assert {"success_rate", "episodes", "correct", "misplaced", "dropped", "boxes_per_minute"} <= set(data)
    assert "success rate" in capsys.readouterr().out


def test_lerobot_train_then_lerobot_eval_run_offline_on_the_cpu(tiny_dataset, tmp_path):
    """The documented commands: lerobot-train on a collected dataset (3 steps), lerobot-eval on ColorSort."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    bin_dir = Path(sys.executable).parent
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    train = subprocess.run([
        str(bin_dir / "lerobot-train"), "--dataset.repo_id=local/colorsort", f"--dataset.root={tiny_dataset}",
        "--dataset.video_backend=pyav", "--policy.type=act", "--policy.device=cpu", "--policy.push_to_hub=false",
        "--policy.pretrained_backbone_weights=null", "--policy.dim_model=64", "--policy.dim_feedforward=128",
        "--policy.n_encoder_layers=1", "--policy.chunk_size=10", "--policy.n_action_steps=10", "--steps=3",
        "--batch_size=2", "--num_workers=0", "--save_freq=3", "--eval_freq=0", "--wandb.enable=false",
        f"--output_dir={tmp_path / 'train'}"], env=env, capture_output=True, text=True, timeout=300)
    assert train.returncode == 0, train.stderr[-3000:]
    checkpoint = tmp_path / "train" / "checkpoints" / "last" / "pretrained_model"
    assert (checkpoint / "model.safetensors").is_file()
    evaluation = subprocess.run([
        str(bin_dir / "lerobot-eval"), "--env.discover_packages_path=colorsort", "--env.type=colorsort",
        "--env.task=ColorSort-Default-v0", "--env.image_size=64", "--env.episode_length=10",
        f"--policy.path={checkpoint}", "--policy.device=cpu", "--eval.n_episodes=1", "--eval.batch_size=1",
        f"--output_dir={tmp_path / 'eval'}"], env=env, capture_output=True, text=True, timeout=300)
    assert evaluation.returncode == 0, evaluation.stderr[-3000:]
    assert "'n_episodes': 1" in evaluation.stdout and "pc_success" in evaluation.stdout
