"""The learned baselines: colorsort-baseline end to end (tiny), its recipes, the shipped checkpoints in both tools."""

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import cv2
import pytest
from helpers import exit_status

from colorsort.cli import baseline as colorsort_baseline
from colorsort.cli.eval import main as eval_main
from colorsort.data.perturbations.brightness import Brightness
from colorsort.data.perturbations.late_pass import LatePass
from colorsort.data.perturbations.late_pick import LatePick
from colorsort.training import cache
from colorsort.training.recipes import RECIPES, get_recipe

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


@pytest.mark.slow
def test_the_pipeline_runs_end_to_end_in_a_tiny_configuration(tmp_path):
    """Two demo counts of one-box demos (each merged with LeRobot's aggregate_datasets), each trained for 2 steps
    with a checkpoint after each, one evaluation episode per variant, the learning curve, the shipped policy; then
    the same command again reuses every finished stage, a shorter run is taken from the longer one, bit for bit
    what lerobot-train makes. (Several training seeds' tables: the pipeline's test with fake stages.)"""
    out, ship = tmp_path / "baseline", tmp_path / "shipped"
    argv = baseline("--recipe", "state", "--demos.counts=1,2", "--demos.train_mix=default:1",
                    "--demos.boxes_per_episode=1", "--demos.late_pass=0", "--training.steps=2",
                    "--training.small_steps=2", "--training.seeds=1000", "--training.save_every=1",
                    "--training.batch_size=2",
                    "--evaluation.variants=default,jitter", "--evaluation.episodes=1",
                    "--evaluation.other_episodes=1", "--evaluation.curve_episodes=1",
                    "--evaluation.episode_length=10", "--workers", "1", "--envs", "1", "--out", str(out))
    first = run(argv + ["--ship", str(ship)], tmp_path, timeout=900)
    assert first.returncode == 0, first.stdout[-3000:] + first.stderr[-3000:]

    results = json.loads((out / "results.json").read_text())
    assert [(r["demos"], r["variant"], r["seed"], r["steps"]) for r in results["rows"]] == [
        (1, "default", 1000, 2), (2, "default", 1000, 2), (2, "jitter", 1000, 2)]
    assert all(r["episodes"] == 1 and r["success_rate"] == 0.0 for r in results["rows"])  # 10 steps sort nothing
    assert [p["step"] for p in results["curve"]] == [1, 2]
    assert 0 < results["curve"][0]["minutes"] <= results["curve"][1]["minutes"]
    curve = [p.name for p in (out / "curve").glob("*.json")]  # step 2's point is the full score's
    assert len(curve) == 1 and re.fullmatch(r"demos-2-\w{8}-2steps-\w{8}-seed1000-chunk10-1-\w{8}\.json", curve[0])
    assert "| default | ACT, state | 2 | 2 steps" in first.stdout
    summary = first.stdout[first.stdout.rindex("| jitter |"):]
    assert summary.startswith("| jitter | ACT, state | 2 | 2 steps")
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    (merged_root,) = (out / "data").glob("demos-2-*")
    assert json.loads((merged_root / "stage.json").read_text())["drop_box_state"] is False
    merged = LeRobotDataset("local/colorsort-baseline", root=merged_root)
    assert merged.num_episodes == 2 and merged.meta.video_keys == []
    for plot in ("success_vs_demos.png", "learning_curve.png"):
        image = cv2.imread(str(out / plot))
        assert image is not None and image.shape[0] > 200 and image.shape[1] > 300

    shipped = {p.name for p in ship.iterdir()}
    assert {"config.json", "model.safetensors", "README.md", "scores.json", "learning_curve.png"} <= shipped
    assert any(name.startswith("policy_preprocessor") for name in shipped)
    readme = (ship / "README.md").read_text()
    assert "colorsort-baseline --recipe state" in readme and "commit" in readme
    assert "| jitter | ACT, state | 2 |" in readme
    assert json.loads((ship / "scores.json").read_text())["rows"] == results["rows"]
    assert eval_main(["--policy", str(ship), "--variant", "default", "--episodes", "1", "--episode-length", "5"]) == 0

    again = run(argv, tmp_path, timeout=600)
    assert again.returncode == 0, again.stderr[-3000:]
    assert again.stdout.count("reusing") == 2 + 2 + 3 + 1 and "lerobot-train" not in again.stdout
    assert run(argv + ["--ship", str(ship)], tmp_path, timeout=600).returncode == 2  # never replaces a shipped policy

    # 1 update: the first update of the 2-update runs, taken, not trained, and what lerobot-train makes of 1
    shorter = run([a.replace("steps=2", "steps=1") for a in argv] + ["--until", "train"], tmp_path, timeout=600)
    assert shorter.returncode == 0, shorter.stderr[-3000:]
    assert shorter.stdout.count("taking the first 1 updates of") == 2 and "lerobot-train" not in shorter.stdout
    fresh = tmp_path / "fresh"
    shutil.copytree(out / "data", fresh / "data")
    trained = run(baseline("--recipe", "state", "--demos.counts=2", "--demos.train_mix=default:1",
                           "--demos.boxes_per_episode=1", "--demos.late_pass=0", "--training.steps=1",
                           "--training.seeds=1000",
                           "--training.batch_size=2", "--workers", "1", "--out", str(fresh), "--until", "train"),
                  tmp_path, timeout=600)
    assert "lerobot-train" in trained.stdout, trained.stdout[-3000:] + trained.stderr[-3000:]
    import torch
    from safetensors.torch import load_file

    (run_name,) = [p.name for p in (fresh / "train").iterdir() if p.is_dir()]
    assert re.fullmatch(r"demos-2-\w{8}-1steps-\w{8}-seed1000", run_name)
    taken, made = (load_file(root / "train" / run_name / "checkpoints" / "last" / "pretrained_model"
                             / "model.safetensors") for root in (out, fresh))
    assert taken.keys() == made.keys() and all(torch.equal(taken[k], made[k]) for k in taken)


@pytest.mark.slow
def test_the_camera_recipe_runs_in_small(tmp_path):
    """The camera recipe, tiny: the policy takes the images and the arm's state, never the simulator's box state,
    and colorsort-eval renders exactly the cameras it was trained on and refuses others."""
    out = tmp_path / "camera"
    result = run(baseline("--recipe", "camera", "--demos.image_size=32", "--demos.counts=1",
                          "--demos.train_mix=default:1", "--demos.boxes_per_episode=1", "--training.steps=2",
                          "--training.batch_size=2", "--evaluation.variants=default", "--evaluation.episodes=1",
                          "--evaluation.curve_episodes=1",
                          "--evaluation.episode_length=5", "--workers", "1", "--envs", "1", "--out", str(out)),
                 tmp_path, timeout=900)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    (data,) = (out / "data").glob("demos-1-*")
    info = json.loads((data / "meta" / "info.json").read_text())
    assert {"observation.images.sensor", "observation.images.wrist"} <= set(info["features"])
    assert "observation.environment_state" not in info["features"]
    (model,) = (out / "train").glob("demos-1-*-2steps-*-seed1000/checkpoints/last/pretrained_model")
    config = json.loads((model / "config.json").read_text())
    assert json.loads((model / "train_config.json").read_text())["dataset"]["image_transforms"]["enable"]  # shifts
    assert set(config["input_features"]) == {"observation.state", "observation.images.sensor",
                                             "observation.images.wrist"}
    assert config["input_features"]["observation.images.wrist"]["shape"] == [3, 32, 32]
    assert config["pretrained_backbone_weights"] is None and config["dim_model"] == 128
    assert "| default | ACT, sensor+wrist | 1 | 2 steps" in result.stdout

    from colorsort.benchmark.evaluate import EpisodeRunner, EvalSettings, observation_settings

    assert observation_settings(str(model), None, None) == (("sensor", "wrist"), (32, 32))
    runner = EpisodeRunner(EvalSettings(str(model), "default", (32, 32), ("sensor", "wrist"), episode_length=3))
    obs, _ = runner.env.reset(seed=0)
    assert set(obs["pixels"]) == {"sensor", "wrist"} and obs["pixels"]["wrist"].shape == (32, 32, 3)
    runner.close()
    assert eval_main(["--policy", str(model), "--variant", "default", "--episodes", "1", "--cameras", "scene"]) == 2
    assert eval_main(["--policy", str(model), "--variant", "default", "--episodes", "1", "--image-size", "64"]) == 2


@pytest.mark.slow
def test_the_tracking_recipe_runs_in_small_and_scores_the_checkpoint_its_validation_seeds_chose(tmp_path):
    """The state-tracking recipe, tiny: its policy takes the tracking belt's 24 state inputs (the encoder too), both
    checkpoints play the validation seeds (never the evaluation seeds), and the chosen one is scored on the
    tracking variants."""
    out = tmp_path / "tracking"
    result = run(baseline("--recipe", "state-tracking", "--demos.counts=1", "--demos.train_mix=tracking:1",
                          "--demos.boxes_per_episode=1", "--training.steps=2", "--training.save_every=1",
                          "--evaluation.select_episodes=1", "--training.batch_size=2",
                          "--evaluation.variants=tracking,tracking-fast", "--evaluation.episodes=1",
                          "--evaluation.other_episodes=1", "--evaluation.curve_episodes=1",
                          "--evaluation.episode_length=5", "--workers", "1", "--envs", "1", "--out", str(out)),
                 tmp_path, timeout=900)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    (run_dir,) = (out / "train").glob("demos-1-*-2steps-*-seed1000")
    config = json.loads((run_dir / "checkpoints" / "last" / "pretrained_model" / "config.json").read_text())
    assert config["input_features"]["observation.state"]["shape"] == [24]
    from colorsort.variants import VALIDATION_SEEDS

    chose = sorted(p.name for p in (out / "select").glob("*.json"))
    assert [name.removeprefix(run_dir.name)[:-14] for name in chose] == ["-ens0.2-1-tracking", "-ens0.2-2-tracking"]
    assert all(json.loads((out / "select" / name).read_text())["seeds"] == [VALIDATION_SEEDS[0]] for name in chose)
    results = json.loads((out / "results.json").read_text())
    assert [(r["variant"], r["checkpoint"]) for r in results["rows"]] == [("tracking", 2), ("tracking-fast", 2)]
    assert re.search(r"scored at 2 after \d+ min \(chosen on validation seeds\)", result.stdout)


@pytest.mark.slow
def test_the_diffusion_camera_recipe_runs_in_small(tmp_path):
    """camera-diffusion, tiny, to its training: lerobot-train's diffusion policy with its GroupNorm ResNet,
    spatial-softmax keypoints and crops; it reads the images and the arm's state only, and colorsort-eval refuses
    other cameras (``test_lerobot_cli`` evaluates a diffusion policy the documented command trained)."""
    out = tmp_path / "diffusion"
    result = run(baseline("--recipe", "camera-diffusion", "--demos.counts=1", "--demos.train_mix=default:1",
                          "--demos.boxes_per_episode=1", "--training.steps=2", "--training.batch_size=2",
                          "--workers", "1", "--out", str(out), "--until", "train"), tmp_path, timeout=900)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    assert "--policy.type=diffusion" in result.stdout
    (run_dir,) = (out / "train").glob("demos-1-*-2steps-*-seed1000")
    model = run_dir / "checkpoints" / "last" / "pretrained_model"
    config = json.loads((model / "config.json").read_text())
    assert config["type"] == "diffusion" and set(config["input_features"]) == {
        "observation.state", "observation.images.sensor", "observation.images.wrist"}
    assert config["input_features"]["observation.images.sensor"]["shape"] == [3, 64, 64]
    assert (config["use_group_norm"], config["crop_shape"], config["pretrained_backbone_weights"]) == (
        True, [58, 58], None)
    assert eval_main(["--policy", str(model), "--variant", "default", "--episodes", "1", "--cameras", "sensor"]) == 2


def test_the_diffusion_recipe_asks_lerobot_train_for_a_small_from_scratch_encoder(tmp_path):
    """Its command line: LeRobot's diffusion type, GroupNorm, no pretrained weights (a download), one shared
    encoder, a crop of 0.9 of the recipe's image side; its settings refuse what LeRobot would reject later."""
    from colorsort.cli.baseline import main
    from colorsort.training.policy_settings import DiffusionSettings
    from colorsort.training.stages import train_command

    recipe = get_recipe("camera-diffusion")
    cmd = train_command(recipe, tmp_path / "demos-48", 5000, 1000, tmp_path / "run")
    for arg in ("--policy.type=diffusion", "--policy.use_group_norm=true", "--policy.pretrained_backbone_weights=null",
                "--policy.use_separate_rgb_encoder_per_camera=false", "--policy.crop_shape=[58,58]",
                "--policy.down_dims=[32,64]", "--policy.n_obs_steps=1", "--policy.num_inference_steps=10"):
        assert arg in cmd
    assert "--policy.crop_shape=[29,29]" in train_command(get_recipe("camera-diffusion", {"demos.image_size": 32}),
                                                          tmp_path, 1, 1, tmp_path)
    assert recipe.policy.execution == "chunk8" and recipe.label.startswith("diffusion, ")
    assert not any(a.startswith("--policy.type=act") or "dim_model" in a for a in cmd)
    with pytest.raises(ValueError, match="multiple of"):
        DiffusionSettings(horizon=10)
    with pytest.raises(ValueError, match="n_action_steps"):
        DiffusionSettings(n_action_steps=17)
    with pytest.raises(ValueError, match="crop_fraction"):
        DiffusionSettings(crop_fraction=0.2)
    assert exit_status(main, ["--recipe", "camera-diffusion", "--policy.lr_schedule=cosine",
                              "--out", str(tmp_path)]) == 2


def test_a_learning_rate_reaches_lerobot_train_for_act_and_names_its_runs_apart(tmp_path):
    """``--policy.optimizer_lr``: ACT's rate in the ``lerobot-train`` command and a run folder of its own (a run at
    another rate is never reused); a policy without the field has no such flag."""
    from colorsort.training.stages import train_command, train_settings

    _, recipe = colorsort_baseline.parse_args(["--recipe", "camera", "--policy.optimizer_lr=3e-4",
                                               "--policy.optimizer_lr_backbone=3e-4"])
    cmd = train_command(recipe, tmp_path / "demos-48", 4000, 1001, tmp_path / "run")
    assert "--policy.optimizer_lr=0.0003" in cmd and "--policy.optimizer_lr_backbone=0.0003" in cmd
    assert cache.key(train_settings(recipe)) != cache.key(train_settings(get_recipe("camera")))
    assert exit_status(colorsort_baseline.main, ["--recipe", "camera-diffusion", "--policy.optimizer_lr=3e-4",
                                                 "--out", str(tmp_path)]) == 2


def test_image_shifts_reach_lerobot_train_as_its_image_transforms(tmp_path):
    """``image_shift``: LeRobot's own image transforms, one random shift per image, and a run folder of its own."""
    import draccus
    import torch
    from lerobot.configs.default import DatasetConfig
    from lerobot.transforms.transforms import ImageTransforms

    from colorsort.training.stages import train_command

    shifted = get_recipe("camera")
    args = shifted.training.augment_args()
    assert shifted.training.image_shift == 0.1
    assert get_recipe("camera", {"training.image_shift": 0}).training.augment_args() == []
    assert set(args) <= set(train_command(shifted, tmp_path, 10, 1000, tmp_path / "run"))
    config = draccus.parse(DatasetConfig, args=["--repo_id=local/x", *[a.replace("--dataset.", "--") for a in args]])
    transforms = ImageTransforms(config.image_transforms)
    image = torch.zeros(3, 32, 32)
    image[:, 12:20, 12:20] = 1.0
    moved = [transforms(image) for _ in range(20)]
    assert all(m.shape == image.shape and m.sum() == image.sum() for m in moved)  # moved whole, no border reached
    offsets = {tuple(torch.nonzero(m[0])[0].tolist()) for m in moved}
    assert len(offsets) > 1 and all(abs(r - 12) <= 3 and abs(c - 12) <= 3 for r, c in offsets)  # 0.1 of 32 px
    for bad in ({"training.image_shift": 0.5}, {"training.image_shift": -0.1}, {"demos.cameras": ()}):
        with pytest.raises(ValueError, match="image_shift"):
            get_recipe("camera", bad)


def test_relit_training_images_vary_as_the_lighting_variant_but_keep_every_box_colour(tmp_path):
    """``image_relight``: LeRobot's ``ColorJitter`` and ``PlanckianJitter`` on every image beside the shift:
    darker and brighter, warmer and colder, and a red, green or blue box keeps its strongest channel."""
    import draccus
    import torch
    from lerobot.configs.default import DatasetConfig
    from lerobot.transforms.transforms import ImageTransforms

    from colorsort.training.stages import train_command

    _, relit = colorsort_baseline.parse_args(["--recipe", "camera", "--training.image_relight=true"])
    args = relit.training.augment_args()
    assert "--dataset.image_transforms.max_num_transforms=3" in args
    assert set(args) <= set(train_command(relit, tmp_path, 10, 1000, tmp_path / "run"))
    config = draccus.parse(DatasetConfig, args=["--repo_id=local/x", *[a.replace("--dataset.", "--") for a in args]])
    transforms = ImageTransforms(config.image_transforms)
    image = torch.full((3, 32, 32), 0.4)  # a grey belt around three saturated boxes
    for channel, (r, c) in enumerate(((4, 4), (4, 20), (20, 12))):
        image[:, r:r + 8, c:c + 8] = 0.1
        image[channel, r:r + 8, c:c + 8] = 0.6
    torch.manual_seed(0)
    relit_images = [transforms(image) for _ in range(40)]
    grey = torch.stack([m[:, 16, 8:24].mean(dim=1) for m in relit_images])  # belt that no 3 px shift moves off
    assert grey.sum(dim=1).min() < 0.8 * 1.2 < 1.2 * 1.2 < grey.sum(dim=1).max()  # dimmer and brighter than 1.2
    assert (grey[:, 0] > grey[:, 2] * 1.1).any() and (grey[:, 2] > grey[:, 0] * 1.1).any()  # warm and cold
    for m in relit_images:
        for channel, (r, c) in enumerate(((4, 4), (4, 20), (20, 12))):
            box = m[:, r + 3:r + 5, c + 3:c + 5].mean(dim=(1, 2))  # the middle of the box, inside any shift
            assert int(box.argmax()) == channel
    with pytest.raises(ValueError, match="image_relight"):
        get_recipe("state", {"training.image_relight": True})


def test_each_training_seed_of_a_shifted_recipe_keeps_its_own_timing(tmp_path, monkeypatch):
    """Each seed's run has a timing file of its own (a learning curve measures minutes from that run's start)."""
    from colorsort.training import stages

    def fake_training(cmd: list[str], log: Path) -> float:  # what lerobot-train leaves, in no time
        run_dir = Path(next(a for a in cmd if a.startswith("--output_dir=")).split("=", 1)[1])
        earlier = len(list(run_dir.parent.glob("*-seed*/"))) if run_dir.parent.exists() else 0
        (run_dir / "checkpoints" / "last" / "pretrained_model").mkdir(parents=True)
        (run_dir / "checkpoints" / "last" / "pretrained_model" / "config.json").write_text("{}")
        return 60.0 * (1 + earlier)

    monkeypatch.setattr(stages, "run", fake_training)
    recipe = get_recipe("camera")
    first = stages.train(recipe, tmp_path / "demos-48", 100, 1000, tmp_path)
    second = stages.train(recipe, tmp_path / "demos-48", 100, 1001, tmp_path)
    assert first[1]["wall_s"] == 60.0 and second[1]["wall_s"] == 120.0
    key = cache.key(stages.train_settings(recipe))
    assert sorted(p.name for p in (tmp_path / "train").glob("*.json")) == [
        f"demos-48-100steps-{key}-seed1000.json", f"demos-48-100steps-{key}-seed1001.json"]
    assert first[1]["settings"] == stages.train_settings(recipe)
    assert stages.train(recipe, tmp_path / "demos-48", 100, 1000, tmp_path) == first  # reused, its own timing


def fake_run(run_dir: Path, steps: int, scheduler: str | None, started: float, seconds_each: float) -> None:
    """What lerobot-train and stages.train leave for a run of ``steps`` updates, one checkpoint an update."""
    for step in range(1, steps + 1):
        model = run_dir / "checkpoints" / f"{step:06d}" / "pretrained_model"
        model.mkdir(parents=True)
        (model / "config.json").write_text(json.dumps({"type": "act", "n_action_steps": 10}))
        (model / "train_config.json").write_text(json.dumps({"steps": steps, "scheduler": scheduler,
                                                             "policy": {"n_action_steps": 10}}))
        (model / "model.safetensors").write_text(f"weights after {step}")
        state = run_dir / "checkpoints" / f"{step:06d}" / "training_state" / "training_step.json"
        state.parent.mkdir()
        state.write_text(json.dumps({"step": step}))
        os.utime(state, (started + step * seconds_each, started + step * seconds_each))
    (run_dir / "checkpoints" / "last").symlink_to(f"{steps:06d}")
    run_dir.with_name(run_dir.name + ".json").write_text(json.dumps({"started": started,
                                                                     "wall_s": steps * seconds_each}))


def test_a_shorter_run_is_the_start_of_a_longer_one_under_a_constant_learning_rate(tmp_path, monkeypatch):
    """With no schedule, a run of 2 updates is the first 2 of a run of 3 with the same data, settings and seed:
    taken from it (checkpoints, save times, its time to reach 2) instead of trained. Never from another seed's
    run, a cosine one (its rate depends on the total) or one without that checkpoint."""
    from colorsort.training import stages

    trained = []
    monkeypatch.setattr(stages, "run", lambda cmd, log: trained.append(cmd) or 0.0)
    train = tmp_path / "train"
    recipe = get_recipe("camera")
    cosine = get_recipe("camera", {"policy.lr_schedule": "cosine"})
    key, cos = cache.key(stages.train_settings(recipe)), cache.key(stages.train_settings(cosine))
    fake_run(train / f"demos-8-3steps-{key}-seed1000", 3, None, started=1e9, seconds_each=600)
    fake_run(train / f"demos-8-5steps-{key}-seed1000", 5, None, started=2e9, seconds_each=60)
    fake_run(train / f"demos-8-3steps-{cos}-seed1001", 3, "cosine_annealing_with_warmup", 1e9, 60)
    fake_run(train / f"demos-8-3steps-{key}-seed1002", 3, None, started=1e9, seconds_each=60)

    run_dir, timing = stages.train(recipe, tmp_path / "demos-8", 2, 1000, tmp_path)
    assert not trained and run_dir.name == f"demos-8-2steps-{key}-seed1000"
    assert timing == {"started": 1e9, "wall_s": 1200.0, "first_updates_of": f"demos-8-3steps-{key}-seed1000"}
    assert sorted(p.name for p in (run_dir / "checkpoints").iterdir()) == ["000001", "000002", "last"]
    assert (run_dir / "checkpoints" / "last" / "pretrained_model" / "model.safetensors").read_text() == \
        "weights after 2"
    assert [(step, minutes) for step, minutes, _ in stages.checkpoints(run_dir, timing)] == [(1, 10.0), (2, 20.0)]
    assert stages.train(recipe, tmp_path / "demos-8", 2, 1000, tmp_path) == (run_dir, timing)  # reused now

    stages.train(recipe, tmp_path / "demos-8", 4, 1000, tmp_path)  # the 5-update run: the shortest with 4
    assert not trained
    stages.train(cosine, tmp_path / "demos-8", 2, 1001, tmp_path)
    stages.train(recipe, tmp_path / "demos-8", 2, 1001, tmp_path)  # seed 1001's only run is another recipe's
    stages.train(recipe, tmp_path / "demos-8", 6, 1002, tmp_path)  # nothing longer than 6
    assert [next(a for a in cmd if a.startswith("--steps=")) for cmd in trained] == ["--steps=2"] * 2 + ["--steps=6"]


def test_a_variant_with_its_own_box_count_is_collected_with_it(tmp_path):
    """``boxes_by_variant``: the seed variant's demos hold one box each, in a part of their own, merged; the merged
    set's key comes from its parts, so another mix is another set, never the seed variant's trained on."""
    from colorsort.training.stages import collect, size

    recipe = get_recipe("state", {"demos.train_mix": (("seed", 1.0),), "demos.counts": (1,),
                                  "demos.boxes_by_variant": (("seed", 1),), "demos.late_pass": LatePass(0)})
    root = collect(recipe, 1, tmp_path, workers=1)
    (part,) = (tmp_path / "data").glob("seed-1-*")
    assert json.loads((part / "meta" / "colorsort.json").read_text())["settings"]["boxes_per_episode"] == 1
    assert "--boxes-per-episode" in json.loads((part / "stage.json").read_text())["colorsort-collect"]
    assert size(root) == size(part) and size(root)[0] == 1
    assert (root / "meta" / "complete").read_text().split() == [part.name]
    assert collect(recipe, 1, tmp_path, workers=1) == root  # reused

    other_mix = get_recipe("state", {"demos.train_mix": (("default", 1.0),), "demos.counts": (1,)})
    other = collect(other_mix, 1, tmp_path, workers=1)
    assert other != root and size(root)[0] == size(other)[0] == 1


def test_a_recipes_perturbations_reach_colorsort_collect_where_they_apply(tmp_path):
    """Each perturbation (``--demos.<name>``) reaches colorsort-collect for the training variants it applies to
    and keys their parts: dim lights for the random-lights variant alone, late picks for both; ``--no-turn`` too.
    One that applies to no training variant (late picks on a tracking belt, dim lights without a lit variant) is
    refused, and a bad value names its range."""
    from colorsort.training.stages import collect, collect_command, size

    _, recipe = colorsort_baseline.parse_args([
        "--recipe", "state", "--demos.train_mix=lighting:1,default:1", "--demos.counts=2",
        "--demos.boxes_per_episode=1", "--demos.late_pass=0", "--demos.brightness=0.45,0.75", "--demos.late_pick=5",
        "--demos.turn_to_box=false"])
    assert [p.name for p in recipe.demos.perturbations] == ["brightness", "late_pick"]
    assert "--brightness=0.45,0.75" not in collect_command(recipe, "default", 1, 1, 1)
    root = collect(recipe, 2, tmp_path, workers=1)
    assert size(root)[0] == 2
    settings = {p.name.split("-")[0]: json.loads((p / "meta" / "colorsort.json").read_text())["settings"]
                for p in (tmp_path / "data").glob("*-1-*")}
    assert settings["lighting"]["brightness"] == [0.45, 0.75] and "brightness" not in settings["default"]
    assert settings["lighting"]["late_pick"] == settings["default"]["late_pick"] == 5
    assert settings["lighting"]["turn_to_box"] is settings["default"]["turn_to_box"] is False
    with pytest.raises(ValueError, match="tracking belt"):
        get_recipe("camera-tracking", {"demos.late_pick": LatePick(30)})
    with pytest.raises(ValueError, match="lighting"):
        get_recipe("state", {"demos.brightness": Brightness(0.45, 0.75)})
    with pytest.raises(ValueError, match="brightness"):
        colorsort_baseline.parse_args(["--recipe", "camera-snapshot", "--demos.brightness=0.9,0.5"])
    with pytest.raises(ValueError, match="late_pick"):
        colorsort_baseline.parse_args(["--recipe", "camera-snapshot", "--demos.late_pick=101"])


def test_bad_settings_name_the_valid_choices(tmp_path, capsys):
    from colorsort.cli.baseline import main

    for argv, named in ((["--recipe", "nope"], "Valid recipes"),
                        (["--demos.train_mix=default:1,nope:1"], "Valid variants"),
                        (["--demos.counts=50,20"], "increasing"),
                        (["--demos.cameras=top"], "Valid cameras"),
                        (["--demos.train_mix=default:x"], "not a valid float"),
                        (["--training.image_relight=maybe"], "true or false"),
                        (["--training.device=tpu"], "valid devices")):
        assert main([*argv, "--out", str(tmp_path)]) == 2, argv
        assert named in capsys.readouterr().err, argv
    assert exit_status(main, ["--until", "later"]) == 2


def test_baseline_help_shows_a_flag_for_every_recipe_field_and_perturbation():
    """``colorsort-baseline --help``: flags generated from the recipe's sections (each with the chosen recipe's
    value) and the perturbation registry; ``Recipe.override`` takes what they parse to, and refuses an unknown key."""
    from dataclasses import fields

    from colorsort.data.perturbations import PERTURBATIONS

    help_text = subprocess.run(baseline("--recipe", "camera-snapshot", "--help"), capture_output=True, text=True,
                               env={**os.environ, "COLUMNS": "1000"}, timeout=60).stdout
    recipe = get_recipe("camera-snapshot")
    for section in ("demos", "policy", "training", "evaluation"):
        for f in fields(getattr(recipe, section)):
            if f.init and f.name != "perturbations":
                assert f"--{section}.{f.name}" in help_text, (section, f.name)
    assert all(f"--demos.{name}" in help_text for name in PERTURBATIONS)
    assert "(recipe 'camera-snapshot': 4000)" in help_text and "(recipe 'camera-snapshot': 10)" in help_text
    with pytest.raises(ValueError, match="Valid settings"):
        recipe.override({"training.stpes": 10})


def test_a_recipe_is_stored_with_its_results_as_json_in_its_sections():
    stored = get_recipe("camera-snapshot").to_json()
    assert json.loads(json.dumps(stored)) == stored
    assert stored["demos"]["perturbations"] == {"brightness": [0.45, 0.75], "late_pass": 100, "late_pick": 10}
    assert stored["policy"]["type"] == "act" and stored["training"]["steps"] == 4000
    from colorsort.training.records import Results
    from colorsort.training.tables import label

    assert label(Results.from_json(scores([], stored))) == "ACT, snapshot"
    assert label(Results.from_json(scores([], {"cameras": ["sensor", "wrist"]}))) == "ACT, sensor+wrist"  # flat


def test_recipes_split_demos_by_weight_and_never_give_a_camera_policy_the_box_state():
    assert get_recipe("state").demos.split(40) == {"default": 8, "jitter": 8, "fast": 8, "distractors": 16}
    camera = get_recipe("camera")
    assert camera.demos.split(48) == {"default": 8, "lighting": 8, "jitter": 8, "fast": 8, "distractors": 16}
    one_box_seed = get_recipe("camera", {"demos.train_mix": camera.demos.train_mix + (("seed", 1),),
                                         "demos.boxes_by_variant": (("seed", 1),)})
    assert (one_box_seed.demos.boxes("seed"), one_box_seed.demos.boxes("jitter")) == (1, camera.demos.boxes_per_episode)
    assert sum(camera.demos.split(7).values()) == 7
    training = camera.training
    assert (training.updates(True, 1000), training.updates(False, 1000)) == (training.steps, training.small_steps)
    with pytest.raises(ValueError, match="at least 1 box"):
        get_recipe("camera", {"demos.boxes_by_variant": (("seed", 0),)})
    with pytest.raises(ValueError, match="Valid variants"):
        get_recipe("camera", {"demos.boxes_by_variant": (("nope", 1),)})
    alike = get_recipe("state", {"demos.counts": (8, 40), "training.passes": 10.0, "training.batch_size": 64})
    assert (alike.training.updates(False, 2560), alike.training.updates(True, 12800)) == (400, 2000)
    with pytest.raises(ValueError, match="seeds"):
        get_recipe("state", {"training.seeds": (1, 1)})
    with pytest.raises(ValueError, match="passes"):
        get_recipe("state", {"training.passes": 0.0})
    for recipe in RECIPES.values():
        assert recipe.evaluation.main_variant in recipe.evaluation.variants
    tracking = get_recipe("camera-tracking")
    assert set(tracking.evaluation.variants) == {"tracking", "tracking-jitter", "tracking-fast"}
    assert tracking.demos.cameras


def test_tracking_acts_chunks_are_temporally_ensembled_and_a_reused_run_takes_the_recipes_inference_settings(
        tmp_path):
    """On the moving belt ACT averages its chunks; the stopping belt's recipes execute 10 actions open-loop.
    Training never reads n_action_steps or temporal_ensemble_coeff, so a reused run (trained with other values)
    gets the recipe's in every checkpoint's config, and its evaluations are filed under the new execution."""
    from colorsort.training.policy_settings import ActSettings
    from colorsort.training.stages import set_inference

    act = get_recipe("camera-tracking").policy
    assert (act.type, act.n_action_steps, act.temporal_ensemble_coeff, act.execution) == ("act", 1, 0.2, "ens0.2")
    assert "--policy.temporal_ensemble_coeff=0.2" in act.args(64) and "--policy.n_action_steps=1" in act.args(64)
    assert get_recipe("state").policy.execution == get_recipe("camera").policy.execution == "chunk10"
    assert get_recipe("state-tracking").policy == act
    with pytest.raises(ValueError, match="n_action_steps=1"):
        ActSettings(n_action_steps=10, temporal_ensemble_coeff=0.01)
    with pytest.raises(ValueError, match="chunk_size"):
        ActSettings(n_action_steps=30)

    run_dir = tmp_path / "run"
    for step in ("000001", "000002"):
        model = run_dir / "checkpoints" / step / "pretrained_model"
        model.mkdir(parents=True)
        (model / "config.json").write_text(json.dumps({"type": "act", "dim_model": 128, "n_action_steps": 10,
                                                       "temporal_ensemble_coeff": None}))
        (model / "train_config.json").write_text(json.dumps({"steps": 2, "policy": {"n_action_steps": 10}}))
    (run_dir / "checkpoints" / "last").symlink_to("000002")
    set_inference(run_dir, get_recipe("camera-tracking"))
    for step in ("000001", "000002", "last"):
        model = run_dir / "checkpoints" / step / "pretrained_model"
        assert json.loads((model / "config.json").read_text()) == {
            "type": "act", "dim_model": 128, "n_action_steps": 1, "temporal_ensemble_coeff": 0.2}
        assert json.loads((model / "train_config.json").read_text()) == {
            "steps": 2, "policy": {"n_action_steps": 1, "temporal_ensemble_coeff": 0.2}}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SHIPPED))
def test_a_shipped_baseline_sorts_through_colorsort_eval(name, tmp_path):
    """README's command for a shipped policy on its main variant's first seed: cameras come from the checkpoint."""
    if not SHIPPED[name].is_dir():
        pytest.skip(f"baselines/{name} is not shipped")
    scores_path = SHIPPED[name] / "scores.json"
    scores = json.loads(scores_path.read_text()) if scores_path.is_file() else {}
    variant = scores.get("recipe", {}).get("main_variant", "default")
    report = tmp_path / "eval.json"
    assert eval_main(["--policy", str(SHIPPED[name]), "--variant", variant, "--episodes", "1",
                      "--json", str(report)]) == 0
    result = json.loads(report.read_text())
    assert result["correct"] >= 1  # it picks and places: not an untrained policy


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SHIPPED))
def test_a_shipped_baseline_runs_in_lerobot_eval(name, tmp_path):
    """README's lerobot-eval command for a shipped policy: it loads and acts, one episode of 100 steps."""
    if not SHIPPED[name].is_dir():
        pytest.skip(f"baselines/{name} is not shipped")
    from colorsort.benchmark.policies import checkpoint_cameras

    cameras, size = checkpoint_cameras(SHIPPED[name])
    task = "ColorSort-Tracking-v0" if "tracking" in name else "ColorSort-Default-v0"
    result = run([str(BIN / "lerobot-eval"), "--env.type=colorsort", f"--env.task={task}",
                  f"--env.cameras={','.join(cameras) or 'none'}", f"--env.image_size={size[0] if size else 128}",
                  f"--policy.path={SHIPPED[name]}", "--policy.device=cpu", "--eval.n_episodes=1",
                  "--eval.batch_size=1", "--env.episode_length=100", f"--output_dir={tmp_path / 'eval'}"],
                 tmp_path, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    overall = json.loads((tmp_path / "eval" / "eval_info.json").read_text())["overall"]
    assert overall["n_episodes"] == 1 and 0 <= overall["pc_success"] <= 100


@pytest.mark.slow
def test_documented_recipe_list_runs_verbatim():
    """docs/baselines.md's `colorsort-baseline --list`, as written: one line per recipe."""
    page = (REPO / "docs" / "baselines.md").read_text()
    assert "colorsort-baseline --list\n" in page
    result = run(baseline("--list"), REPO, timeout=120)
    assert result.returncode == 0, result.stderr
    assert [line.split()[0] for line in result.stdout.splitlines()] == list(RECIPES)


def test_docs_tables_are_the_ones_scores_json_gives():
    """Every scores block in README and docs/ is what `python tools/baseline_tables.py` writes from its JSON;
    every shipped baseline with scores.json has its table in the docs."""
    from colorsort.training.tables import fill, pages

    text = {page: page.read_text() for page in pages(REPO)}
    for page, body in text.items():
        assert fill(body, REPO) == body, f"{page} is stale: run python tools/baseline_tables.py"
    for name, path in SHIPPED.items():
        if (path / "scores.json").is_file():
            assert any(f"<!-- scores baselines/{name} table -->" in t for t in text.values()), name


def test_training_times_over_seeds_read_as_one_figure_when_they_round_alike():
    from colorsort.training.report import span

    assert span([53.6, 53.9, 54.2]) == "54"
    assert span([49.2, 57.4]) == "49-57"
    assert span([42.0]) == "42"


def test_a_stale_scores_block_is_rewritten_and_a_bad_one_refused():
    from colorsort.training.tables import fill

    stale = "before\n<!-- scores baselines/act-camera curve -->\n| old | numbers |\n<!-- end scores -->\nafter\n"
    new = fill(stale, REPO)
    assert "| old |" not in new and "| updates | training [min] |" in new
    assert new.startswith("before\n") and new.endswith("<!-- end scores -->\nafter\n") and fill(new, REPO) == new
    with pytest.raises(ValueError, match="Valid kinds"):
        fill("<!-- scores baselines/act-camera plot -->\n<!-- end scores -->", REPO)
    with pytest.raises(ValueError, match="no scores.json"):
        fill("<!-- scores baselines/nothing table -->\n<!-- end scores -->", REPO)


def test_the_headline_gives_a_baseline_of_several_seeds_its_mean_and_range(tmp_path):
    """One seed: the rate with its Wilson interval; three seeds: their mean and range, never one cell per seed."""
    from colorsort.training.tables import headline

    def row(variant: str, seed: int, rate: float) -> dict:
        return score_row(variant=variant, seed=seed, success_rate=rate, success_ci95=[rate - 0.1, rate + 0.05])

    for name, rows in (("one", [row("default", 1000, 0.9)]),
                       ("three", [row(v, s, r) for s, r in ((1000, 0.9), (1001, 0.6), (1002, 0.75))
                                  for v in ("default", "fast")])):
        (tmp_path / name).mkdir()
        (tmp_path / name / "scores.json").write_text(json.dumps(scores(rows)))
    point = {"episodes": 10, "successes": 5, "correct": 15, "misplaced": 0, "dropped": 0}
    chosen = [{**row("default", s, 1.0), "checkpoint": c,
               "validation": [{"step": 2500, "minutes": 10.0, **point}, {"step": 5000, "minutes": 20.0, **point}]}
              for s, c in ((1000, 5000), (1001, 2500))]
    (tmp_path / "two").mkdir()
    (tmp_path / "two" / "scores.json").write_text(json.dumps(scores(chosen)))
    one, three, two = headline(tmp_path).splitlines()[2:]
    assert "`default` 90% (80-95%, 50)" in one and "20 min on the CPU |" in one
    assert "`default` mean 75%, seeds 60-90% (3 x 50); `fast` mean 75%" in three
    assert "per seed, 3 seeds" in three and three.count("`default`") == 1
    # each run scored at the checkpoint its validation seeds chose: the training time is that checkpoint's
    assert "5000 updates, scored at 5000/2500 (chosen on validation seeds), 10-20 min on the CPU per seed" in two


@pytest.mark.parametrize("variant", ["robots-panda", "tracking"])
def test_a_checkpoint_on_a_variant_it_does_not_fit_gets_a_one_line_error(variant, capsys):
    """act-state takes 23 state inputs: the Panda's state has 25, a tracking belt's 24."""
    assert eval_main(["--policy", str(SHIPPED["act-state"]), "--variant", variant, "--episodes", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"cannot run on {variant}" in err and "'default'" in err


def test_a_recipe_scored_on_a_variant_its_policy_cannot_run_on_gets_a_one_line_error(capsys, tmp_path):
    """The pipeline refuses before collecting anything: a stopping-belt policy cannot run on a tracking belt."""
    from colorsort.cli.baseline import main as baseline_main

    out = tmp_path / "never"
    assert baseline_main(["--recipe", "state", "--evaluation.variants=default,tracking", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "['tracking'] do not fit" in err and "'distractors'" in err
    assert not out.exists()


@pytest.mark.slow
def test_variant_all_runs_each_shipped_baseline_on_exactly_the_variants_it_fits(capsys):
    """A stopping-belt policy (23 state inputs) skips the tracking variants (24) and the Panda (25); the tracking
    policy runs on the three tracking variants only; every skipped variant is named with its reason."""
    from colorsort.cli.eval import variant_names

    tracking = ["tracking", "tracking-fast", "tracking-jitter"]
    for name, path in SHIPPED.items():
        if not path.is_dir():
            continue
        fits = variant_names(str(path), "all")
        skipped = capsys.readouterr().err
        if "tracking" in name:
            assert fits == tracking
        else:
            assert not set(fits) & {*tracking, "robots-panda"}
            assert {"seed", "default", "fast", "jitter", "lighting", "distractors"} <= set(fits)
        assert all(f"skipping {v}:" in skipped for v in ["robots-panda", *(set(tracking) - set(fits))])


@pytest.mark.slow
def test_an_execution_is_the_same_checkpoint_acting_as_named(tmp_path):
    """``with_execution``'s copy of a checkpoint executes as named: LeRobot loads it with that many open-loop steps or
    with its temporal ensembler; the weights are the shipped ones; a bad name is refused."""
    from colorsort.benchmark.execution import inference_settings, with_execution
    from colorsort.benchmark.policies import LeRobotPolicy

    chunked = LeRobotPolicy(with_execution(SHIPPED["act-state"], "chunk5", tmp_path)).policy
    ensembled = LeRobotPolicy(with_execution(SHIPPED["act-state"], "ens0.01", tmp_path)).policy
    assert (chunked.config.n_action_steps, chunked.config.temporal_ensemble_coeff) == (5, None)
    assert ensembled.config.n_action_steps == 1 and ensembled.temporal_ensembler.chunk_size == 20
    assert (tmp_path / "chunk5" / "model.safetensors").read_bytes() == (
        SHIPPED["act-state"] / "model.safetensors").read_bytes()
    with pytest.raises(ValueError, match="chunkN"):
        inference_settings("open10")


def test_executions_are_compared_on_each_variant_named_and_on_validation_seeds_when_asked(monkeypatch):
    """``execution_table``: one row per variant and execution, each scored on that variant; ``validation`` plays the
    validation seeds (from 20000), never the evaluation seeds; an unknown variant or execution stops before any
    episode runs."""
    from types import SimpleNamespace

    from colorsort.benchmark import evaluate as evaluation
    from colorsort.benchmark.execution import execution_table
    from colorsort.variants import VALIDATION_SEEDS

    played = []

    def fake_evaluate(policy, variant, episodes, **kwargs):
        played.append((Path(policy).name, variant, kwargs["seed"]))
        return SimpleNamespace(success_ci95=(0.0, 1.0), success_rate=1.0, correct=3, misplaced=0, dropped=0,
                               distractors_let_through=0, distractors=0)

    monkeypatch.setattr(evaluation, "evaluate", fake_evaluate)
    policy = str(SHIPPED["act-state"])
    for validation, first in ((False, None), (True, VALIDATION_SEEDS[0])):
        played.clear()
        lines = list(execution_table(policy, ["default", "distractors"], ["chunk10", "ens0.2"], 2, 1, validation))
        assert played == [(e, v, first) for v in ("default", "distractors") for e in ("chunk10", "ens0.2")]
        assert [line.split(" | ")[:2] for line in lines[3:]] == [["| default", "chunk10"], ["| default", "ens0.2"],
                                                                 ["| distractors", "chunk10"],
                                                                 ["| distractors", "ens0.2"]]
    assert "first 2 validation seeds" in lines[0]
    played.clear()
    for variants, executions, named in ((["default", "nope"], ["chunk10"], "Valid variants"),
                                        (["default"], ["open10"], "chunkN")):
        with pytest.raises(ValueError, match=named):
            list(execution_table(policy, variants, executions, 1))
    assert not played


@pytest.mark.parametrize("name", list(SHIPPED))
def test_a_shipped_scores_json_reads_as_typed_records_and_writes_back_unchanged(name):
    """Results as typed records: every shipped scores.json reads into ``Results`` and writes back the same JSON, so
    the records change no figure of a shipped baseline."""
    from colorsort.training.records import Results

    stored = json.loads((SHIPPED[name] / "scores.json").read_text())
    results = Results.from_json(stored)
    assert results.to_json() == {**stored, "curve": stored.get("curve") or []}
    assert all(r.report.episodes == len(r.report.per_episode) for r in results.rows)


def test_the_mistakes_table_counts_each_wrong_bin_by_colour_over_every_seed():
    """Two seeds' misplaced boxes add up per (colour, bin); correct and dropped boxes and smaller demo counts do not."""
    from colorsort.training.records import Results
    from colorsort.training.tables import render

    def row(seed: int, demos: int, boxes: list[tuple[str, str, str | None]]) -> dict:
        episode = {"boxes": [{"color": c, "outcome": o, "bin": b} for c, o, b in boxes]}
        return score_row(demos_tried=demos, variant="jitter", seed=seed, per_episode=[episode])

    rows = [row(1000, 48, [("red", "misplaced", "green"), ("blue", "correct", "blue"), ("red", "dropped", None)]),
            row(1001, 48, [("red", "misplaced", "green"), ("blue", "misplaced", "green")]),
            row(1000, 8, [("green", "misplaced", "red")])]
    table = render(Results.from_json(scores(rows)), "mistakes")
    assert table.splitlines()[2] == "| jitter | 3 | red -> green 2, blue -> green 1 |"
    clean = [row(1000, 48, [("red", "correct", "red")])]
    assert render(Results.from_json(scores(clean)), "mistakes").endswith("| every variant | 0 | |")


def test_a_shipped_readme_says_how_the_demos_were_made():
    """The README's demo line gives each variant's count, with the perturbations that act on some variants only
    after them, and those on every variant once at the end, each as it describes itself."""
    from colorsort.training.ship import demo_line

    assert demo_line(get_recipe("camera-snapshot")) == (
        "8 on default, 8 on lighting under lights of brightness x0.45-0.75, 8 on jitter, 8 on fast, 16 on "
        "distractors; 3 boxes each; every belt pass held back 0-100 steps; every pick held back 0-10 steps")
    assert demo_line(get_recipe("state", {"demos.late_pass": LatePass(0), "demos.late_pick": LatePick(5)})) == (
        "8 on default, 8 on jitter, 8 on fast, 16 on distractors; 3 boxes each; every pick held back 0-5 steps")
    assert demo_line(get_recipe("camera-tracking")) == "24 on tracking, 24 on tracking-jitter; 5 boxes each"


def test_first_box_delay_is_the_median_over_the_seeds_both_runs_placed_a_box(tmp_path):
    """``colorsort-analyze first-box-delay``: seed 1's first placed box 0.5 s later, seed 2's 1.0 s, seed 3 placed
    nothing in one run (left out): median 0.75 s over 2 seeds; two runs with no seed in common are refused."""
    def evaluation(times: dict[int, list[tuple[float, str]]]) -> dict:
        return {"variant": "default", "mean_cycle_time_s": 4.0, "per_episode": [
            {"seed": s, "boxes": [{"time": t, "outcome": o} for t, o in boxes]} for s, boxes in times.items()]}

    new = evaluation({1: [(7.5, "placed"), (12.0, "placed")], 2: [(6.0, "dropped"), (9.0, "placed")],
                      3: [(8.0, "placed")]})
    old = evaluation({1: [(7.0, "placed")], 2: [(8.0, "placed")], 3: [(8.0, "dropped")]})
    (tmp_path / "new.json").write_text(json.dumps(new))
    (tmp_path / "old.json").write_text(json.dumps(old))
    out = run([str(BIN / "colorsort-analyze"), "first-box-delay", "new.json", "old.json"], tmp_path, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("first box placed +0.75 s later (median over 2 seeds, default)")
    (tmp_path / "other.json").write_text(json.dumps(evaluation({9: [(7.0, "placed")]})))
    refused = run([str(BIN / "colorsort-analyze"), "first-box-delay", "new.json", "other.json"], tmp_path,
                  timeout=60)
    assert refused.returncode == 2 and "no evaluation seed where both runs placed a box" in refused.stderr


def test_a_reshipped_baseline_names_its_commit_clean_when_only_its_own_folder_changed(tmp_path, monkeypatch):
    """Reshipping replaces the tracked files of the folder it ships to: that alone is no uncommitted change."""
    from colorsort.training.ship import commit

    def git(*args: str) -> None:
        subprocess.run(["git", *args], cwd=tmp_path, check=True, capture_output=True)

    git("init", "-q")
    (tmp_path / "baselines" / "p").mkdir(parents=True)
    (tmp_path / "baselines" / "p" / "model.safetensors").write_text("old weights")
    (tmp_path / "code.py").write_text("x = 1\n")
    git("add", ".")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "one")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "baselines" / "p" / "model.safetensors").write_text("new weights")
    assert not commit(Path("baselines/p")).endswith("(with uncommitted changes)")
    assert commit().endswith("(with uncommitted changes)")
    (tmp_path / "code.py").write_text("x = 2\n")
    assert commit(Path("baselines/p")).endswith("(with uncommitted changes)")


def test_compare_scores_puts_two_runs_side_by_side_per_variant(tmp_path):
    """``colorsort-analyze compare``: each seed's rate, their mean, and box counts summed over the seeds; a variant only
    one run has gets a dash on the other side."""
    def row(variant: str, rate: float, correct: int, misplaced: int) -> dict:
        return score_row(demos_tried=48, variant=variant, success_rate=rate, correct=correct, misplaced=misplaced)

    new = scores([row("seed", 1.0, 40, 0), row("seed", 0.5, 20, 10), row("jitter", 0.25, 9, 6)])
    old = scores([row("seed", 0.25, 10, 12)])
    for name, run_scores in (("new.json", new), ("old.json", old)):
        (tmp_path / name).write_text(json.dumps(run_scores))
    out = run([str(BIN / "colorsort-analyze"), "compare", "new.json", "old.json", "--labels", "a,b"], tmp_path, 60)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0].startswith("| variant | a: mean (each seed) | b: mean (each seed) |")
    assert lines[2] == "| `seed` | 75% (100%, 50%) | 25% (25%) | 60 / 10 / 0 | 10 / 12 / 0 |"
    assert lines[3] == "| `jitter` | 25% (25%) | - | 9 / 6 / 0 | - |"
    assert lines[4] == "| every variant (mean of the variants' means) | 50% | 25% | | |"


def test_loading_a_checkpoint_prints_nothing_into_a_benchmarks_recorded_figures(capsys):
    """LeRobot's "Loading weights from local directory" stays out of stdout, which benchmarks record to docs/results."""
    from colorsort.benchmark.policies import LeRobotPolicy

    capsys.readouterr()
    LeRobotPolicy(SHIPPED["act-state"])
    assert capsys.readouterr().out == ""


def test_the_checkpoint_scored_is_chosen_on_validation_seeds_never_the_evaluation_seeds(tmp_path, monkeypatch):
    """A recipe with select_episodes plays every checkpoint of each seed's run on the validation seeds of each
    training variant; the one with the most successes there (ties: most boxes right, then the later) is scored on
    the evaluation seeds, shipped, marked in the tables, and its point on the learning curve is its full score's."""
    from colorsort.training import pipeline, ship, stages
    from colorsort.variants import EVAL_SEEDS, VALIDATION_SEEDS

    assert not set(VALIDATION_SEEDS) & set(EVAL_SEEDS)
    validation = {  # successes on the validation seeds, per (seed, update): seed 1000 peaks at 2, 1001 ties 2 and 3
        (1000, 1): 1, (1000, 2): 4, (1000, 3): 2, (1001, 1): 0, (1001, 2): 3, (1001, 3): 3}
    evaluated: list[tuple[str, str, int | None]] = []

    def fake_evaluate(recipe, model, variant, episodes, stem, envs, log_dir, first_seed=None):
        step = int(Path(model).parent.name) if Path(model).parent.name.isdigit() else 3
        seed = int(str(model).split("-seed")[1][:4])
        evaluated.append((Path(model).parent.name, variant, first_seed))
        successes = validation[seed, step] // 2 if first_seed is not None else step
        episodes_run = 2 if first_seed is not None else episodes
        return {"policy": str(model), "variant": variant, "episodes": episodes_run, "successes": successes,
                "success_rate": successes / episodes_run, "success_ci95": [0.0, 1.0], "correct": 3 * successes,
                "misplaced": 0, "dropped": 0, "distractors": 0, "distractors_let_through": 0,
                "boxes_per_minute": 1.0, "mean_cycle_time_s": 2.0,
                "per_episode": [{"success": k < successes, "correct": 3 * (k < successes), "misplaced": 0,
                                 "dropped": 0} for k in range(episodes_run)]}

    def fake_train(recipe, data, steps, seed, out):
        run_dir = out / "train" / f"{data.name}-{steps}steps-seed{seed}"
        fake_run(run_dir, steps, None, started=1e9, seconds_each=60)
        return run_dir, json.loads(run_dir.with_name(run_dir.name + ".json").read_text())

    monkeypatch.setattr(stages, "collect", lambda recipe, n, out, workers: out / "data" / f"demos-{n}")
    monkeypatch.setattr(stages, "size", lambda data: (4, 400))
    monkeypatch.setattr(stages, "train", fake_train)
    monkeypatch.setattr(stages, "evaluate", fake_evaluate)
    monkeypatch.setattr(ship, "parameters", lambda model: 1000)  # the fake runs' weights are text
    recipe = get_recipe("state-tracking", {
        "demos.counts": (4,), "training.steps": 3, "training.save_every": 1, "evaluation.select_episodes": 2,
        "training.seeds": (1000, 1001), "evaluation.variants": ("tracking", "tracking-jitter"),
        "evaluation.episodes": 4, "evaluation.other_episodes": 4, "evaluation.curve_episodes": 4})
    ship_to = tmp_path / "shipped"
    results = pipeline.run_pipeline(recipe, pipeline.RunSettings(tmp_path / "out", envs=1), "cmd", ship_to)

    first = VALIDATION_SEEDS[0]
    chose = [e for e in evaluated if e[2] is not None]
    assert chose == [(f"{s:06d}", v, first) for _ in (1000, 1001) for s in (1, 2, 3)
                     for v in ("tracking", "tracking-jitter")]
    scored = [(e[0], e[1]) for e in evaluated if e[2] is None]
    assert scored[:2] == [("000002", "tracking"), ("000002", "tracking-jitter")]  # seed 1000: update 2
    assert scored[-2:] == [("last", "tracking"), ("last", "tracking-jitter")]  # seed 1001's tie: the later (3)
    assert [(r.seed, r.checkpoint, r.report.success_rate) for r in results.rows] == [
        (1000, 2, 0.5), (1000, 2, 0.5), (1001, 3, 0.75), (1001, 3, 0.75)]
    assert [p.successes for p in results.rows[0].validation] == [0, 4, 2]  # 2 variants, half each
    assert [(p.step, p.successes) for p in results.curve] == [(1, 1), (2, 2), (3, 3)]
    assert (ship_to / "model.safetensors").read_text() == "weights after 2"
    readme = (ship_to / "README.md").read_text()
    assert "scored at 2/3 after 2/3 min (chosen on validation seeds)" in readme and "| 1000 | 2 (chosen) |" in readme
    assert f"({first} on, never scored" in readme
    with pytest.raises(ValueError, match="save_every"):
        get_recipe("camera-tracking", {"training.save_every": 0})
    with pytest.raises(ValueError, match="validation seeds"):
        get_recipe("camera-tracking", {"evaluation.select_episodes": len(VALIDATION_SEEDS) + 1})
