"""colorsort-baseline's pipeline: tiny end-to-end runs of its recipes, its stages' reuse, the checkpoint
chosen on validation seeds, a shipped README."""

import json
import os
import re
import shutil
import subprocess
import time
from pathlib import Path

import cv2
import pytest
import torch
from baseline_common import run_in_process

from colorsort.cli import baseline as colorsort_baseline
from colorsort.cli.eval import main as eval_main
from colorsort.data.perturbations.brightness import Brightness
from colorsort.data.perturbations.late_pass import LatePass
from colorsort.data.perturbations.late_pick import LatePick
from colorsort.training import cache
from colorsort.training import pipeline_stages as stages
from colorsort.training.recipes import get_recipe


@pytest.fixture
def in_process(monkeypatch):
    """Every stage's command (colorsort-collect, colorsort-eval, colorsort-takeover, lerobot-train) run by its own
    entry point in this process, not a new interpreter each."""
    monkeypatch.setattr(stages, "run", run_in_process)


def baseline_main(argv: list[str], capsys) -> tuple[int, str]:
    """``colorsort-baseline argv`` in this process: (exit status, what it printed)."""
    capsys.readouterr()
    status = colorsort_baseline.main(argv)
    return status, capsys.readouterr().out


@pytest.mark.slow
def test_the_pipeline_runs_end_to_end_in_a_tiny_configuration(tmp_path, in_process, capsys):
    """The state-tracking recipe, tiny: two one-box demos on the belt that never stops (merged with LeRobot's
    aggregate_datasets), trained for 2 steps with a checkpoint after each; both checkpoints play
    the validation seeds (never the evaluation seeds) and the chosen one is scored, one episode per variant; the
    learning curve; the shipped policy, which takes the tracking belt's 24 state inputs. Then the same command again
    reuses every finished stage, a shorter run is taken from the longer one, bit for bit what lerobot-train
    makes, and a run interrupted after a checkpoint resumes from it. (Several training seeds' tables: the
    pipeline's test with fake stages.)"""
    from colorsort.variants import VALIDATION_SEEDS

    out, ship = tmp_path / "baseline", tmp_path / "shipped"
    argv = ["--recipe", "state-tracking", "--demos.counts=2", "--demos.train_mix=tracking:1",
            "--demos.boxes_per_episode=1", "--training.steps=2", "--training.small_steps=2",
            "--training.seeds=1000", "--training.save_every=1", "--training.batch_size=2", "--training.num_workers=0",
            "--evaluation.select_episodes=1", "--evaluation.variants=tracking,tracking-fast",
            "--evaluation.episodes=1", "--evaluation.other_episodes=1", "--evaluation.curve_episodes=1",
            "--evaluation.episode_length=10", "--workers", "1", "--envs", "1", "--out", str(out)]
    status, first = baseline_main(argv + ["--ship", str(ship)], capsys)
    assert status == 0, first[-3000:]

    results = json.loads((out / "results.json").read_text())
    assert [(r["demos"], r["variant"], r["seed"], r["steps"], r["checkpoint"]) for r in results["rows"]] == [
        (2, "tracking", 1000, 2, 2), (2, "tracking-fast", 1000, 2, 2)]
    assert all(r["episodes"] == 1 and r["success_rate"] == 0.0 for r in results["rows"])  # 10 steps sort nothing
    assert [p["step"] for p in results["curve"]] == [1, 2]
    assert 0 <= results["curve"][0]["minutes"] <= results["curve"][1]["minutes"]  # to 0.1 min: 2 updates take s
    (run_dir,) = [p for p in (out / "train").iterdir() if p.is_dir()]
    saved = stages.checkpoints(run_dir, json.loads(run_dir.with_name(run_dir.name + ".json").read_text()))
    assert [step for step, _, _ in saved] == [1, 2] and 0 < saved[0][1] <= saved[1][1]  # minutes from the run's start
    curve = [p.name for p in (out / "curve").glob("*.json")]  # step 2's point is the full score's
    assert len(curve) == 1 and re.fullmatch(r"demos-2-\w{8}-2steps-\w{8}-seed1000-ens0.2-1-\w{8}\.json", curve[0])
    chose = sorted(p.name for p in (out / "select").glob("*.json"))  # 2 checkpoints x 1 training variant
    assert len(chose) == 2 and all("-tracking-" in name for name in chose)
    assert all(json.loads((out / "select" / name).read_text())["seeds"] == [VALIDATION_SEEDS[0]] for name in chose)
    assert re.search(r"scored at 2 after \d+ min \(chosen on validation seeds\)", first)
    assert "| tracking | ACT, state | 2 | 2 steps" in first
    summary = first[first.rindex("| tracking-fast |"):]
    assert summary.startswith("| tracking-fast | ACT, state | 2 | 2 steps")
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
    assert "colorsort-baseline --recipe state-tracking" in readme and "commit" in readme
    assert "| tracking-fast | ACT, state | 2 |" in readme and "| 2 (chosen) |" in readme
    assert "trains the same weights, bit for bit" in readme  # test_the_same_training_command_gives_... holds it
    assert json.loads((ship / "scores.json").read_text())["rows"] == results["rows"]
    assert json.loads((ship / "config.json").read_text())["input_features"]["observation.state"]["shape"] == [24]
    assert eval_main(["--policy", str(ship), "--variant", "tracking", "--episodes", "1", "--episode-length", "5"]) == 0

    status, again = baseline_main(argv, capsys)
    assert status == 0 and again.count("reusing") == 1 + 1 + 2 + 2 + 1 and "lerobot-train" not in again
    assert baseline_main(argv + ["--ship", str(ship)], capsys)[0] == 2  # never replaces a shipped policy

    # 1 update: the first update of the 2-update runs, taken, not trained, and what lerobot-train makes of 1
    status, shorter = baseline_main([a.replace("steps=2", "steps=1") for a in argv] + ["--until", "train"], capsys)
    assert status == 0 and shorter.count("taking the first 1 updates of") == 1 and "lerobot-train" not in shorter
    fresh = tmp_path / "fresh"
    shutil.copytree(out / "data", fresh / "data")
    status, trained = baseline_main(["--recipe", "state-tracking", "--demos.counts=2", "--demos.train_mix=tracking:1",
                                     "--demos.boxes_per_episode=1", "--training.steps=1", "--training.seeds=1000",
                                     "--training.batch_size=2", "--training.num_workers=0", "--workers", "1",
                                     "--out", str(fresh), "--until", "train"], capsys)
    assert status == 0 and "lerobot-train" in trained, trained[-3000:]
    import torch
    from safetensors.torch import load_file

    (run_name,) = [p.name for p in (fresh / "train").iterdir() if p.is_dir()]
    assert re.fullmatch(r"demos-2-\w{8}-1steps-\w{8}-seed1000", run_name)
    taken, made = (load_file(root / "train" / run_name / "checkpoints" / "last" / "pretrained_model"
                             / "model.safetensors") for root in (out, fresh))
    assert taken.keys() == made.keys() and all(torch.equal(taken[k], made[k]) for k in taken)

    # interrupted after its first checkpoint (as a killed run leaves it), the 2-update run resumes from there: from
    # its weights and its optimizer's state (Adam's step count goes on to 2); the wait is not counted as training
    run_dir = out / "train" / run_dir.name
    whole = load_file(run_dir / "checkpoints" / "000002" / "pretrained_model" / "model.safetensors")
    after_one = load_file(run_dir / "checkpoints" / "000001" / "pretrained_model" / "model.safetensors")
    shutil.rmtree(run_dir / "checkpoints" / "000002")
    (run_dir / "checkpoints" / "last").unlink()
    (run_dir / "checkpoints" / "last").symlink_to("000001")
    first_saved = (run_dir / "checkpoints" / "000001" / "training_state" / "training_step.json").stat().st_mtime
    run_dir.with_name(run_dir.name + ".json").unlink()
    run_dir.with_name(run_dir.name + ".running.json").write_text(json.dumps(
        {"started": first_saved - 30, "settings": {}, "resumed": []}))
    time.sleep(2)  # the gap between the interruption and the resumption
    status, resumed = baseline_main(argv + ["--until", "train"], capsys)
    assert status == 0 and f"resuming {run_dir} after 1 updates" in resumed and "removing" not in resumed
    again = load_file(run_dir / "checkpoints" / "last" / "pretrained_model" / "model.safetensors")
    assert again.keys() == whole.keys() and not all(torch.equal(again[k], after_one[k]) for k in whole)
    adam = load_file(run_dir / "checkpoints" / "last" / "training_state" / "optimizer_state.safetensors")
    counts = {float(v) for k, v in adam.items() if k.endswith("/step")}
    assert counts == {2.0}, counts
    timing = json.loads(run_dir.with_name(run_dir.name + ".json").read_text())
    assert not run_dir.with_name(run_dir.name + ".running.json").exists()
    (resumption,) = timing["resumed"]
    assert resumption["step"] == 1 and resumption["kept_s"] == 30.0 and resumption["gap_s"] >= 2
    saved = stages.checkpoints(run_dir, timing)
    assert [step for step, _, _ in saved] == [1, 2]
    assert saved[0][1] == pytest.approx(0.5, abs=0.01) and 0.5 < saved[1][1] <= timing["wall_s"] / 60 + 0.01


@pytest.mark.slow
def test_the_camera_recipe_runs_in_small(tmp_path, in_process, capsys):
    """The camera recipe, tiny: the policy takes the images and the arm's state, never the simulator's box state,
    and colorsort-eval renders exactly the cameras it was trained on and refuses others."""
    out = tmp_path / "camera"
    status, printed = baseline_main(["--recipe", "camera", "--demos.image_size=32", "--demos.counts=1",
                                     "--demos.train_mix=default:1", "--demos.boxes_per_episode=1",
                                     "--training.steps=2", "--training.seeds=1000", "--training.batch_size=2",
                                     "--training.num_workers=0", "--evaluation.variants=default",
                                     "--evaluation.episodes=1", "--evaluation.curve_episodes=1",
                                     "--evaluation.episode_length=5",
                                     "--workers", "1", "--envs", "1", "--out", str(out)], capsys)
    assert status == 0, printed[-3000:]
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
    assert "| default | ACT, sensor+wrist | 1 | 2 steps" in printed

    from colorsort.benchmark.evaluate import EpisodeRunner, EvalConfig, observation_settings

    assert observation_settings(str(model), None, None) == (("sensor", "wrist"), (32, 32))
    runner = EpisodeRunner(EvalConfig(str(model), "default", (32, 32), ("sensor", "wrist"), episode_length=3))
    obs, _ = runner.env.reset(seed=0)
    assert set(obs["pixels"]) == {"sensor", "wrist"} and obs["pixels"]["wrist"].shape == (32, 32, 3)
    runner.close()
    assert eval_main(["--policy", str(model), "--variant", "default", "--episodes", "1", "--cameras", "scene"]) == 2
    assert eval_main(["--policy", str(model), "--variant", "default", "--episodes", "1", "--image-size", "64"]) == 2


@pytest.mark.slow
def test_the_diffusion_camera_recipe_runs_in_small(tmp_path, in_process, capsys):
    """camera-diffusion, tiny: LeRobot's diffusion policy learns from the images and the arm's state, never the box
    state (2 updates), and colorsort-eval renders exactly its cameras at its image size. Trained in float32 first,
    the recipe's float16 run is that run's weights rounded (no second training), scored as stored, and LeRobot loads
    the halved file into its float32 model; the run with each checkpoint the mean of the latest two is that run's
    checkpoints averaged (no third training)."""
    from lerobot.policies.diffusion.modeling_diffusion import DiffusionPolicy
    from safetensors.torch import load_file

    from colorsort.benchmark.evaluate import observation_settings

    out = tmp_path / "diffusion"
    argv = ["--recipe", "camera-diffusion", "--demos.counts=1", "--demos.train_mix=lighting:1",
            "--demos.boxes_per_episode=1", "--training.steps=2", "--training.seeds=1000", "--training.batch_size=2",
            "--training.num_workers=0", "--evaluation.variants=default", "--evaluation.episodes=1",
            "--evaluation.curve_episodes=1", "--evaluation.episode_length=5", "--training.save_every=1",
            "--evaluation.select_episodes=0", "--workers", "1", "--envs", "1", "--out", str(out)]
    status, printed = baseline_main(argv + ["--training.weights=float32"], capsys)
    assert status == 0, printed[-3000:]
    (full,) = (out / "train").glob("demos-1-*-2steps-*-seed1000")
    model = full / "checkpoints" / "last" / "pretrained_model"
    config = json.loads((model / "config.json").read_text())
    assert config["type"] == "diffusion"
    assert set(config["input_features"]) == {"observation.state", "observation.images.snapshot"}
    assert (config["prediction_type"], config["noise_scheduler_type"]) == ("sample", "DDIM")
    assert observation_settings(str(model), None, None) == (("snapshot",), (64, 64))
    assert f"| default | {get_recipe('camera-diffusion').label} | 1 | 2 steps" in printed

    status, printed = baseline_main(argv, capsys)
    assert status == 0, printed[-3000:]
    assert f"copying {full}'s checkpoints in float16\n" in printed and "lerobot-train" not in printed
    (halved,) = set((out / "train").glob("demos-1-*-2steps-*-seed1000")) - {full}
    stored = load_file(halved / "checkpoints" / "last" / "pretrained_model" / "model.safetensors")
    assert {t.dtype for t in stored.values() if t.is_floating_point()} == {torch.float16}
    assert any(halved.name in p.name for p in (out / "eval").glob("*.json"))  # scored as stored
    policy = DiffusionPolicy.from_pretrained(halved / "checkpoints" / "last" / "pretrained_model")
    weights = dict(policy.named_parameters())
    name = next(k for k in stored if k in weights and stored[k].ndim > 1)
    assert weights[name].dtype == torch.float32 and torch.equal(weights[name], stored[name].float())

    status, printed = baseline_main(argv + ["--training.average=2"], capsys)
    assert status == 0, printed[-3000:]
    assert f"copying {full}'s checkpoints in float16, each the mean of the latest 2" in printed
    assert "lerobot-train" not in printed
    (averaged,) = set((out / "train").glob("demos-1-*-2steps-*-seed1000")) - {full, halved}
    ours = load_file(averaged / "checkpoints" / "000002" / "pretrained_model" / "model.safetensors")[name]
    first, last = (load_file(full / "checkpoints" / step / "pretrained_model" / "model.safetensors")[name]
                   for step in ("000001", "000002"))
    assert ours.dtype == torch.float16 and torch.equal(ours, ((first.double() + last.double()) / 2).half())


@pytest.mark.slow
def test_a_dagger_round_adds_the_experts_labels_of_the_policys_states_and_trains_again(tmp_path, in_process, capsys):
    """--dagger.rounds=1, tiny, from the cameras: the first policy plays a `default` episode, the expert takes over
    after 5 steps and labels the states from there (their own task text, the demos' cameras and video codec), the
    labels join the demo, a second policy is trained on both from scratch and is the one scored, its minutes (the
    row's and each checkpoint's) counting both trainings; the same command again reuses every stage."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from colorsort.training.takeover import PROVENANCE, TAKEOVER_SEED, TAKEOVER_TASK

    out = tmp_path / "dagger"
    argv = ["--recipe", "camera", "--demos.counts=1", "--demos.train_mix=default:1", "--demos.boxes_per_episode=1",
            "--training.steps=2", "--training.seeds=1000", "--training.batch_size=2", "--training.num_workers=0",
            "--dagger.rounds=1", "--dagger.episodes=1", "--dagger.handover=5:5", "--evaluation.variants=default",
            "--evaluation.episodes=1", "--evaluation.curve_episodes=1", "--evaluation.episode_length=5",
            "--workers", "1", "--envs", "1", "--out", str(out)]
    status, printed = baseline_main(argv, capsys)
    assert status == 0, printed[-3000:]
    (demos,) = (out / "data").glob("demos-1-????????")
    (labels,) = (out / "data").glob("labels-default-r1-*")
    (merged,) = (out / "data").glob("demos-1-dagger1-*")
    first, second = (sorted((out / "train").glob(f"{d.name}-2steps-*-seed1000")) for d in (demos, merged))
    assert len(first) == len(second) == 1
    provenance = json.loads((labels / "meta" / PROVENANCE).read_text())
    assert provenance["policy"] == str(first[0] / "checkpoints" / "last" / "pretrained_model")
    assert provenance["kept"] == [TAKEOVER_SEED] and provenance["handed_over_at"] == {str(TAKEOVER_SEED): 5}
    root = {d: LeRobotDataset("local/colorsort-baseline", root=d) for d in (demos, labels, merged)}
    assert root[merged].num_episodes == root[demos].num_episodes + 1
    assert root[merged].num_frames == root[demos].num_frames + root[labels].num_frames
    assert TAKEOVER_TASK in set(root[merged].meta.tasks.index) and len(root[merged].meta.tasks) == 2
    videos = {key: root[demos].meta.features[key] for key in root[demos].meta.video_keys}
    assert videos and {key: root[labels].meta.features[key] for key in videos} == videos  # codec included
    assert "observation.environment_state" not in root[merged].meta.features  # the camera recipe's inputs
    assert root[merged][len(root[merged]) - 1]["observation.images.sensor"].shape == (3, 32, 32)
    results = json.loads((out / "results.json").read_text())
    (row,) = results["rows"]
    assert row["frames"] == root[merged].num_frames and results["recipe"]["dagger"]["rounds"] == 1
    walls = [json.loads(run.with_name(run.name + ".json").read_text())["wall_s"] for run in (first[0], second[0])]
    assert row["train_minutes"] == pytest.approx(sum(walls) / 60, abs=0.01)  # both rounds' training
    # the last checkpoint's minutes: the first round's training, then the second's up to that save (0.1 min rounding)
    started = json.loads(second[0].with_name(second[0].name + ".json").read_text())["started"]
    saved = (second[0] / "checkpoints" / "last" / "training_state" / "training_step.json").stat().st_mtime
    assert results["curve"][-1]["minutes"] == pytest.approx((walls[0] + saved - started) / 60, abs=0.051)
    assert list((out / "eval").glob(f"{second[0].name}-*-default-*.json"))  # the second policy is scored
    assert f"| default | {get_recipe('camera', {'dagger.rounds': 1}).label} | 1 |" in printed

    status, again = baseline_main(argv, capsys)
    assert status == 0, again[-3000:]
    assert all(f"reusing {p}" in again for p in (labels, merged, second[0]))


@pytest.mark.slow
def test_a_finetuning_dagger_round_trains_the_policy_that_played_further(tmp_path, in_process, capsys):
    """--dagger.retrain=finetune --dagger.updates=1, tiny, on the belt that never stops: the round's lerobot-train
    starts from the weights of the checkpoint that played (``--policy.path``; one Adam update moves no weight by
    much more than the learning rate, where a new policy's weights are its own), trains for the round's updates on
    the demos and the labels, is named after the checkpoint it started from, and is the one scored; the table calls
    it fine-tuned and its minutes count both trainings."""
    from safetensors.torch import load_file

    out = tmp_path / "finetune"
    argv = ["--recipe", "state-tracking", "--demos.counts=1", "--demos.train_mix=tracking:1",
            "--demos.boxes_per_episode=1", "--training.steps=2", "--training.seeds=1000", "--training.batch_size=2",
            "--training.num_workers=0", "--dagger.rounds=1", "--dagger.episodes=1", "--dagger.handover=5:5",
            "--dagger.retrain=finetune", "--dagger.updates=1", "--evaluation.variants=tracking",
            "--evaluation.episodes=1", "--evaluation.curve_episodes=1", "--evaluation.episode_length=5",
            "--workers", "1", "--envs", "1", "--out", str(out)]
    status, printed = baseline_main(argv, capsys)
    assert status == 0, printed[-3000:]
    (demos,) = (out / "data").glob("demos-1-????????")
    (merged,) = (out / "data").glob("demos-1-dagger1-*")
    (first,) = (out / "train").glob(f"{demos.name}-2steps-*-seed1000")
    (second,) = (out / "train").glob(f"{merged.name}-1steps-*-seed1000")
    played = first / "checkpoints" / "last" / "pretrained_model"
    tuned = second / "checkpoints" / "last" / "pretrained_model"
    config = json.loads((tuned / "train_config.json").read_text())
    assert config["policy"]["pretrained_path"] == str(played) and config["steps"] == 1
    assert json.loads(second.with_name(second.name + ".json").read_text())["settings"]["from"] == first.name
    before, after = (load_file(m / "model.safetensors") for m in (played, tuned))
    lr = config["policy"]["optimizer_lr"]
    moved = max(float((after[k] - before[k]).abs().max()) for k in before)
    assert 0 < moved < 5 * lr  # one update from the played weights (a fresh initialisation differs by ~0.1)
    results = json.loads((out / "results.json").read_text())
    (row,) = results["rows"]
    assert row["steps"] == 1 and results["recipe"]["dagger"]["retrain"] == "finetune"
    walls = [json.loads(run.with_name(run.name + ".json").read_text())["wall_s"] for run in (first, second)]
    assert row["train_minutes"] == pytest.approx(sum(walls) / 60, abs=0.01)
    assert list((out / "eval").glob(f"{second.name}-*-tracking-*.json"))
    assert "ACT + DAgger (1 round, fine-tuned), state" in printed
    with pytest.raises(ValueError, match=r"\['scratch', 'finetune'\]"):
        get_recipe("state-tracking", {"dagger.rounds": 1, "dagger.retrain": "warm"})
    with pytest.raises(ValueError, match="updates=-1"):
        get_recipe("state-tracking", {"dagger.rounds": 1, "dagger.updates": -1})


def test_each_training_seed_of_a_shifted_recipe_keeps_its_own_timing(tmp_path, monkeypatch):
    """Each seed's run has a timing file of its own (a learning curve measures minutes from that run's start)."""
    from colorsort.training import pipeline_stages as stages

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


def test_a_run_resumed_twice_counts_only_the_training_it_kept(tmp_path, monkeypatch):
    """Killed after its first checkpoint, resumed, killed again before the next one and resumed again: the run's
    training time is the time to its first checkpoint plus the last segment's; the waits and the lost updates are
    not, and its checkpoints' minutes agree with that. lerobot-train is asked to resume, into the same folder."""
    from colorsort.training import pipeline_stages as stages

    recipe = get_recipe("camera")
    run_dir = tmp_path / "train" / f"demos-8-2steps-{cache.key(stages.train_settings(recipe))}-seed1000"
    now = time.time()
    started = now - 1000
    fake_run(run_dir, 1, None, started=started, seconds_each=100)  # checkpoint 1 saved at started + 100
    run_dir.with_name(run_dir.name + ".json").unlink()  # killed: no timing, the marker instead
    first = {"step": 1, "at": started + 500, "kept_s": 100.0, "gap_s": 400.0}
    run_dir.with_name(run_dir.name + ".running.json").write_text(json.dumps(
        {"started": started, "settings": {"s": 1}, "resumed": [first]}))
    commands = []

    def resumed_training(cmd: list[str], log: Path, append: bool = False) -> float:
        commands.append((cmd, append))
        fake_checkpoint = run_dir / "checkpoints" / "000002"
        shutil.copytree(run_dir / "checkpoints" / "000001", fake_checkpoint)
        os.utime(fake_checkpoint / "training_state" / "training_step.json", (now + 60, now + 60))
        (run_dir / "checkpoints" / "last").unlink()
        (run_dir / "checkpoints" / "last").symlink_to("000002")
        return 60.0

    monkeypatch.setattr(stages, "run", resumed_training)
    out_dir, timing = stages.train(recipe, tmp_path / "demos-8", 2, 1000, tmp_path)
    ((cmd, append),) = commands
    assert out_dir == run_dir and append and "--resume=true" in cmd and f"--output_dir={run_dir}" in cmd
    assert f"--config_path={run_dir}/checkpoints/last/pretrained_model/train_config.json" in cmd
    assert timing["resumed"][0] == first and timing["resumed"][1]["kept_s"] == 0.0
    assert timing["resumed"][1]["gap_s"] == pytest.approx(500, abs=5)
    assert timing["wall_s"] == pytest.approx(160, abs=5) and timing["settings"] == {"s": 1}
    minutes = [m for _, m, _ in stages.checkpoints(run_dir, timing)]
    assert minutes == pytest.approx([100 / 60, 160 / 60], abs=0.1)
    assert not run_dir.with_name(run_dir.name + ".running.json").exists()
    assert stages.train(recipe, tmp_path / "demos-8", 2, 1000, tmp_path) == (run_dir, timing)  # finished: reused


def test_a_shorter_run_is_the_start_of_a_longer_one_under_a_constant_learning_rate(tmp_path, monkeypatch):
    """With no schedule, a run of 2 updates is the first 2 of a run of 3 with the same data, settings and seed:
    taken from it (checkpoints, save times, its time to reach 2) instead of trained. Never from another seed's
    run, a cosine one (its rate depends on the total) or one without that checkpoint."""
    from colorsort.training import pipeline_stages as stages

    trained = []
    monkeypatch.setattr(stages, "run", lambda cmd, log, append=False: trained.append(cmd) or 0.0)
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


@pytest.mark.slow
def test_a_variant_with_its_own_box_count_is_collected_with_it(tmp_path, in_process):
    """``boxes_by_variant``: the seed variant's demos hold one box each, in a part of their own, merged; the merged
    set's key comes from its parts, so another mix is another set, never the seed variant's trained on."""
    from colorsort.training.pipeline_stages import collect_demos as collect
    from colorsort.training.pipeline_stages import size

    recipe = get_recipe("state", {"demos.train_mix": (("seed", 1.0),), "demos.counts": (1,),
                                  "demos.boxes_by_variant": (("seed", 1),), "demos.late_pass": LatePass(0)})
    root = collect(recipe, 1, tmp_path, workers=1)
    (part,) = (tmp_path / "data").glob("seed-1-*")
    assert json.loads((part / "meta" / "colorsort.json").read_text())["settings"]["boxes_per_episode"] == 1
    assert json.loads((part / "stage.json").read_text())["collect"]["boxes_per_episode"] == 1  # in its key
    assert size(root) == size(part) and size(root)[0] == 1
    assert (root / "meta" / "complete").read_text().split() == [part.name]
    assert collect(recipe, 1, tmp_path, workers=1) == root  # reused

    other_mix = get_recipe("state", {"demos.train_mix": (("default", 1.0),), "demos.counts": (1,)})
    other = collect(other_mix, 1, tmp_path, workers=1)
    assert other != root and size(root)[0] == size(other)[0] == 1


@pytest.mark.slow
def test_a_recipes_perturbations_reach_colorsort_collect_where_they_apply(tmp_path, in_process):
    """Each perturbation (``--demos.<name>``) reaches colorsort-collect for the training variants it applies to
    and keys their parts: dim lights for the random-lights variant alone, late picks for both; ``--no-turn`` too.
    One that applies to no training variant (late picks on a tracking belt, dim lights without a lit variant) is
    refused, and a bad value names its range."""
    from colorsort.training.pipeline_stages import collect_command, size
    from colorsort.training.pipeline_stages import collect_demos as collect

    recipe = colorsort_baseline.chosen_recipe([
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
        colorsort_baseline.chosen_recipe(["--recipe", "camera-snapshot", "--demos.brightness=0.9,0.5"])
    with pytest.raises(ValueError, match="late_pick"):
        colorsort_baseline.chosen_recipe(["--recipe", "camera-snapshot", "--demos.late_pick=101"])


def test_tracking_acts_chunks_are_temporally_ensembled_and_a_reused_run_takes_the_recipes_inference_settings(
        tmp_path):
    """On the moving belt ACT averages its chunks; the stopping belt's recipes execute 10 actions open-loop.
    Training never reads n_action_steps or temporal_ensemble_coeff, so a reused run (trained with other values)
    gets the recipe's in every checkpoint's config, and its evaluations are filed under the new execution."""
    from colorsort.training.pipeline_stages import set_inference
    from colorsort.training.policy_config import ActConfig

    act = get_recipe("camera-tracking").policy
    assert (act.type, act.n_action_steps, act.temporal_ensemble_coeff, act.execution) == ("act", 1, 0.2, "ens0.2")
    assert "--policy.temporal_ensemble_coeff=0.2" in act.args(64) and "--policy.n_action_steps=1" in act.args(64)
    assert get_recipe("state").policy.execution == get_recipe("camera").policy.execution == "chunk10"
    assert get_recipe("state-tracking").policy == act
    with pytest.raises(ValueError, match="n_action_steps=1"):
        ActConfig(n_action_steps=10, temporal_ensemble_coeff=0.01)
    with pytest.raises(ValueError, match="chunk_size"):
        ActConfig(n_action_steps=30)

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


def fake_stages(monkeypatch, successes, minutes_each) -> list[tuple[str, str, int | None, str]]:
    """The pipeline's stages faked: 4 demos of 400 frames, runs of one checkpoint an update (``fake_run``, each
    update ``minutes_each(seed)`` long), every evaluation ``successes(seed, step, validating)`` successes of 2
    episodes on validation seeds, of all asked for otherwise. The evaluations run, as (checkpoint folder, variant,
    first validation seed or None, stage folder), filled as the pipeline runs."""
    from colorsort.training.publishing import ship

    evaluated: list[tuple[str, str, int | None, str]] = []

    def fake_evaluate(recipe, model, variant, episodes, stem, envs, log_dir, first_seed=None):
        step = int(Path(model).parent.name) if Path(model).parent.name.isdigit() else 3
        seed = int(str(model).split("-seed")[1][:4])
        evaluated.append((Path(model).parent.name, variant, first_seed, stem.parent.name))
        won = successes(seed, step, first_seed is not None)
        n = 2 if first_seed is not None else episodes
        return {"policy": str(model), "variant": variant, "episodes": n, "successes": won,
                "success_rate": won / n, "success_ci95": [0.0, 1.0], "correct": 3 * won, "misplaced": 0,
                "dropped": 0, "distractors": 0, "distractors_let_through": 0, "boxes_per_minute": 1.0,
                "mean_cycle_time_s": 2.0, "per_episode": [{"success": k < won, "correct": 3 * (k < won),
                                                           "misplaced": 0, "dropped": 0} for k in range(n)]}

    def fake_train(recipe, data, steps, seed, out, init=None):
        start = "" if init is None else f"-from-{stages.checkpoint_name(init)}"
        run_dir = out / "train" / f"{data.name}-{steps}steps{start}-seed{seed}"
        fake_run(run_dir, steps, None, started=1e9, seconds_each=minutes_each(seed))
        return run_dir, json.loads(run_dir.with_name(run_dir.name + ".json").read_text())

    monkeypatch.setattr(stages, "collect_demos", lambda recipe, n, out, workers: out / "data" / f"demos-{n}")
    monkeypatch.setattr(stages, "size", lambda data: (4, 400))
    monkeypatch.setattr(stages, "train", fake_train)
    monkeypatch.setattr(stages, "score_policy", fake_evaluate)
    monkeypatch.setattr(ship, "parameters", lambda model: 1000)  # the fake runs' weights are text
    return evaluated


def test_the_checkpoint_scored_is_chosen_on_validation_seeds_never_the_evaluation_seeds(tmp_path, monkeypatch):
    """A recipe with select_episodes plays every checkpoint of each seed's run on the validation seeds of each
    training variant; the one with the most successes there (ties: most boxes right, then the later) is scored on
    the evaluation seeds, shipped, marked in the tables, and its point on the learning curve is its full score's."""
    from colorsort.training import pipeline
    from colorsort.variants import EVAL_SEEDS, VALIDATION_SEEDS

    assert not set(VALIDATION_SEEDS) & set(EVAL_SEEDS)
    validation = {  # successes on the validation seeds, per (seed, update): seed 1000 peaks at 2, 1001 ties 2 and 3
        (1000, 1): 1, (1000, 2): 4, (1000, 3): 2, (1001, 1): 0, (1001, 2): 3, (1001, 3): 3}
    evaluated = fake_stages(monkeypatch, lambda seed, step, validating: validation[seed, step] // 2 if validating
                            else step, lambda seed: 60)
    recipe = get_recipe("state-tracking", {
        "demos.counts": (4,), "training.steps": 3, "training.save_every": 1, "evaluation.select_episodes": 2,
        "training.seeds": (1000, 1001), "evaluation.variants": ("tracking", "tracking-jitter"),
        "evaluation.episodes": 4, "evaluation.other_episodes": 4, "evaluation.curve_episodes": 4})
    ship_to = tmp_path / "shipped"
    results = pipeline.run_pipeline(recipe, pipeline.RunConfig(tmp_path / "out", envs=1), "cmd", ship_to)

    first = VALIDATION_SEEDS[0]
    chose = [e[:3] for e in evaluated if e[2] is not None]
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


def test_a_dagger_round_rolls_out_the_last_checkpoint_or_the_one_validation_chooses(tmp_path, monkeypatch):
    """dagger.rollout="last" (the default) has the round's takeover driven by the first training's last checkpoint;
    "chosen" by the checkpoint its validation seeds choose, named in the labels' cache key; the retrained policy is
    chosen and scored as ever. "chosen" without validation episodes: ValueError naming both settings."""
    from colorsort.training import pipeline

    validation = {1: 0, 2: 2, 3: 1}  # the first training peaks at update 2; the retraining at 3
    evaluated = fake_stages(monkeypatch, lambda seed, step, validating: validation[step] if validating else 4,
                            lambda seed: 60)
    drove: list[tuple[str, str, str]] = []

    def fake_label(recipe, model, variant, k, round_, out):
        drove.append((model.parents[1].parent.name, model.parent.name, stages.checkpoint_name(model)))
        return out / "data" / f"labels-{variant}-r{round_}"

    monkeypatch.setattr(stages, "label", fake_label)
    monkeypatch.setattr(stages, "add_labels", lambda recipe, data, labels, stem, out: out / "data" / stem)
    flags = {"demos.counts": (4,), "demos.train_mix": (("tracking", 1),), "training.steps": 3,
             "training.save_every": 1, "training.seeds": (1000,), "evaluation.select_episodes": 2,
             "evaluation.variants": ("tracking",), "evaluation.episodes": 4, "evaluation.curve_episodes": 4,
             "dagger.rounds": 1}
    run = "demos-4-3steps-seed1000"
    for rollout, checkpoint, key in (("last", "last", run), ("chosen", "000002", f"{run}@2")):
        drove.clear()
        recipe = get_recipe("state-tracking", {**flags, "dagger.rollout": rollout})
        results = pipeline.run_pipeline(recipe, pipeline.RunConfig(tmp_path / rollout, envs=1), "cmd")
        assert drove == [(run, checkpoint, key)]  # the labels' cache key names the update unless it is the last
        assert [(r.seed, r.checkpoint) for r in results.rows] == [(1000, 2)]
        assert {e[3] for e in evaluated if e[0] == "000002" and e[2] is None} == {"eval"}
        assert results.recipe["dagger"]["rollout"] == rollout
        evaluated.clear()
    with pytest.raises(ValueError, match="rollout='chosen'.*select_episodes"):
        get_recipe("state-tracking", {**flags, "dagger.rollout": "chosen", "evaluation.select_episodes": 0})
    with pytest.raises(ValueError, match=r"\['last', 'chosen'\]"):
        get_recipe("state-tracking", {**flags, "dagger.rollout": "best"})


def test_a_dagger_round_plays_only_the_variants_it_names_with_their_own_takeover_seeds(tmp_path, monkeypatch):
    """dagger.variants=("tracking-jitter",) on a two-variant mix: the round's takeover plays that variant alone,
    as the second training variant (so with the seeds it has when both are played), and its labels alone join."""
    from colorsort.training import pipeline

    fake_stages(monkeypatch, lambda seed, step, validating: 2, lambda seed: 60)
    played: list[tuple[str, int]] = []
    joined: list[list[str]] = []

    def fake_label(recipe, model, variant, k, round_, out):
        played.append((variant, k))
        return out / "data" / f"labels-{variant}-r{round_}"

    def fake_add_labels(recipe, data, labels, stem, out):
        joined.append([p.name for p in labels])
        return out / "data" / stem

    monkeypatch.setattr(stages, "label", fake_label)
    monkeypatch.setattr(stages, "add_labels", fake_add_labels)
    flags = {"demos.counts": (4,), "demos.train_mix": (("tracking", 1), ("tracking-jitter", 1)),
             "training.steps": 2, "training.seeds": (1000,), "evaluation.variants": ("tracking",),
             "evaluation.episodes": 4, "dagger.rounds": 1}
    for variants, expected in (((), [("tracking", 0), ("tracking-jitter", 1)]),
                               (("tracking-jitter",), [("tracking-jitter", 1)])):
        played.clear()
        joined.clear()
        recipe = get_recipe("state-tracking", {**flags, "dagger.variants": variants})
        pipeline.run_pipeline(recipe, pipeline.RunConfig(tmp_path / (variants[0] if variants else "all"), envs=1),
                              "cmd")
        assert played == expected
        assert joined == [[f"labels-{v}-r1" for v, _ in expected]]


def test_a_baseline_stored_before_a_setting_existed_takes_seeds_of_its_recipe_at_that_settings_default():
    """act-camera-tracking-dagger's scores.json predates dagger.rollout: a later seed of its own recipe may join it
    (the setting ran as its default, "last"), and a run with rollout="chosen" may not."""
    from colorsort.errors import ConfigError
    from colorsort.training.publishing.ship import addable

    shipped = Path(__file__).parents[1] / "baselines" / "act-camera-tracking-dagger"
    assert "rollout" not in json.loads((shipped / "scores.json").read_text())["recipe"]["dagger"]
    same = {"training.seeds": (1003,), "evaluation.other_episodes": 50, "dagger.rounds": 1, "dagger.episodes": 24,
            "dagger.handover": (20, 100)}
    assert addable(get_recipe("camera-tracking", same), shipped).seeds == (1001, 1000, 1002)
    with pytest.raises(ConfigError, match=r"\['dagger.rollout'\]"):
        addable(get_recipe("camera-tracking", {**same, "dagger.rollout": "chosen"}), shipped)


def test_training_seeds_run_in_a_later_sitting_join_the_baseline_shipped_before(tmp_path, monkeypatch, capsys):
    """``--add-to DIR`` adds a later run's training seeds (the same recipe and flags, other seeds) to the baseline
    shipped in DIR: its scores, tables and README gain their rows and the sitting, its policy and learning curve stay
    the first seed's; another recipe, a seed it holds, no baseline there, or --ship beside it: exit 2, nothing run."""
    from colorsort.training.publishing import tables
    from colorsort.training.results_file import PipelineResults

    best = {(1000, 2): 2, (1001, 3): 2}  # successes on the validation seeds, per (seed, update); else 0
    evaluated = fake_stages(monkeypatch, lambda seed, step, validating: best.get((seed, step), 0) if validating
                            else seed - 999, lambda seed: 60 * (seed - 999))
    flags = ["--recipe", "state-tracking", "--demos.counts=4", "--training.steps=3", "--training.save_every=1",
             "--evaluation.select_episodes=2", "--evaluation.variants=tracking,tracking-jitter",
             "--evaluation.episodes=4", "--evaluation.other_episodes=4", "--evaluation.curve_episodes=4"]
    shipped = tmp_path / "shipped"
    first = flags + ["--training.seeds=1000", "--out", str(tmp_path / "one"), "--ship", str(shipped)]
    assert baseline_main(first, capsys)[0] == 0
    curve_png = (shipped / "learning_curve.png").read_bytes()
    before = PipelineResults.load(shipped / "scores.json")
    assert before.seeds == (1000,) and before.commit and not before.added

    later = flags + ["--training.seeds=1001", "--out", str(tmp_path / "two")]
    for argv, says in ((later + ["--add-to", str(tmp_path / "none")], "no scores.json"),
                       (later + ["--add-to", str(shipped), "--ship", str(tmp_path / "x")], "give one of them"),
                       ([a.replace("steps=3", "steps=4") for a in later] + ["--add-to", str(shipped)],
                        "['training.steps']"),
                       ([a.replace("1001", "1000") for a in later] + ["--add-to", str(shipped)], "seeds [1000]")):
        capsys.readouterr()
        assert colorsort_baseline.main(argv) == 2 and says in capsys.readouterr().err
    assert not (tmp_path / "two").exists()  # refused before any stage ran

    evaluated.clear()
    status, printed = baseline_main(later + ["--add-to", str(shipped)], capsys)
    assert status == 0 and "added training seeds [1001] to" in printed
    assert "curve" not in [e[3] for e in evaluated]  # the baseline's curve is its first seed's
    after = PipelineResults.load(shipped / "scores.json")
    assert after.seeds == (1000, 1001) and after.recipe["training"]["seeds"] == [1000, 1001]
    assert after.rows[:2] == before.rows and [(r.seed, r.checkpoint) for r in after.rows[2:]] == [(1001, 3)] * 2
    assert after.curve == before.curve and after.commit == before.commit and after.command == before.command
    (sitting,) = after.added
    assert sitting.seeds == (1001,) and sitting.command.endswith(f"--add-to {shipped}") and sitting.commit
    assert (shipped / "model.safetensors").read_text() == "weights after 2"  # seed 1000's chosen checkpoint
    assert (shipped / "seed1001" / "model.safetensors").read_text() == "weights after 3"  # seed 1001's, kept
    assert (shipped / "learning_curve.png").read_bytes() == curve_png
    readme = (shipped / "README.md").read_text()
    assert f"Training seed 1001 added later by `{sitting.command}`" in readme
    assert "The policy of training seed 1001 (its checkpoint scored below) is in `seed1001/`" in readme
    assert "each of the recipe's 2 training seeds (1000, 1001; this policy is seed 1000's)" in readme
    assert "| tracking | ACT, state | 4 | 3 steps (0.5 passes), scored at 2/3 after 2/6 min" in readme
    assert "| 1001 | 3 (chosen) |" in readme
    assert "38% (25-50%), 2 seeds | 25%, 50%" in tables.render(after, "table")  # seed 1000: 1 of 4, 1001: 2 of 4
    page = f"<!-- scores {shipped.name} table -->\n<!-- end scores -->"
    assert f"; seed 1001 added by {sitting.command}):" in tables.fill_baseline_tables(page, tmp_path)
    assert colorsort_baseline.main(later + ["--add-to", str(shipped)]) == 2  # seed 1001 is there now
    assert "already holds training seeds [1001] with their policies" in capsys.readouterr().err


def test_a_held_seed_run_again_is_kept_when_it_reproduces_its_rows_and_replaces_them_only_when_asked(tmp_path,
                                                                                                   monkeypatch,
                                                                                                   capsys):
    """A seed a baseline holds without its policy (added before baselines kept them) may be run again with
    ``--add-to``: a run that reproduces every episode and validation point the seed scored keeps its policy in
    ``seed<N>/`` and its sitting, the rows as they were; one that scores otherwise changes nothing, exit 2, unless
    ``--replace-seeds`` says to replace the seed's rows with its own."""
    from colorsort.training.results_file import PipelineResults

    flags = ["--recipe", "state-tracking", "--demos.counts=4", "--training.steps=3", "--training.save_every=1",
             "--evaluation.select_episodes=2", "--evaluation.variants=tracking", "--evaluation.episodes=4",
             "--evaluation.curve_episodes=4"]
    shipped = tmp_path / "shipped"
    fake_stages(monkeypatch, lambda seed, step, validating: step - 1, lambda seed: 60)
    assert baseline_main(flags + ["--training.seeds=1000", "--out", str(tmp_path / "one"), "--ship",
                                  str(shipped)], capsys)[0] == 0
    later = flags + ["--training.seeds=1001", "--add-to", str(shipped)]
    assert baseline_main(later + ["--out", str(tmp_path / "two")], capsys)[0] == 0
    shutil.rmtree(shipped / "seed1001")  # as a baseline of before: seed 1001's rows, not its weights
    before = (shipped / "scores.json").read_text()

    fake_stages(monkeypatch, lambda seed, step, validating: step - 1 - (seed == 1001 and not validating), lambda s: 60)
    capsys.readouterr()
    assert colorsort_baseline.main(later + ["--out", str(tmp_path / "three")]) == 2
    said = capsys.readouterr().err
    assert "training seeds [1001] scored otherwise than" in said and "{1001: ['tracking']}" in said
    assert "--replace-seeds" in said
    assert (shipped / "scores.json").read_text() == before and not (shipped / "seed1001").exists()

    fake_stages(monkeypatch, lambda seed, step, validating: step - 1, lambda seed: 90)  # slower: minutes differ
    status, printed = baseline_main(later + ["--out", str(tmp_path / "four")], capsys)
    assert status == 0 and "training seeds [1001] reproduced every episode" in printed
    assert (shipped / "seed1001" / "model.safetensors").read_text() == "weights after 3"
    after, held = PipelineResults.load(shipped / "scores.json"), PipelineResults.from_json(json.loads(before))
    assert after.rows == held.rows and after.added == held.added and after.seeds == (1000, 1001)
    (sitting,) = after.kept
    assert sitting.seeds == (1001,) and str(tmp_path / "four") in sitting.command
    readme = (shipped / "README.md").read_text()
    assert f"Training seed 1001 run again by `{sitting.command}`" in readme and "`seed1001/`" in readme

    # scored otherwise, with --replace-seeds: the seed's rows are the new run's, the sitting that made the old ones
    # is recorded as replaced, the others stay
    shutil.rmtree(shipped / "seed1001")
    assert colorsort_baseline.main(flags + ["--training.seeds=1001", "--replace-seeds=true"]) == 2  # no --add-to
    fake_stages(monkeypatch, lambda seed, step, validating: step - 1 - (seed == 1001 and not validating), lambda s: 60)
    status, printed = baseline_main(later + ["--out", str(tmp_path / "five"), "--replace-seeds=true"], capsys)
    assert status == 0 and "the rows of [1001] replaced" in printed
    replaced = PipelineResults.load(shipped / "scores.json")
    assert [r for r in replaced.rows if r.seed == 1000] == [r for r in held.rows if r.seed == 1000]
    (row,) = [r for r in replaced.rows if r.seed == 1001]
    assert row.report.successes == 1 and replaced.seeds == (1000, 1001)  # 2 of 4 before
    assert [s.seeds for s in replaced.replaced] == [(1001,)] and replaced.replaced[0] == held.added[0]
    assert not replaced.kept  # the run that reproduced the old rows no longer describes any
    (now,) = replaced.added
    assert str(tmp_path / "five") in now.command and now.seeds == (1001,)
    assert (shipped / "seed1001" / "model.safetensors").read_text() == "weights after 3"
    readme = (shipped / "README.md").read_text()
    assert f"Training seed 1001 first added by `{held.added[0].command}`" in readme


def test_a_reshipped_baseline_names_its_commit_clean_when_only_its_own_folder_changed(tmp_path, monkeypatch):
    """Reshipping replaces the tracked files of the folder it ships to: that alone is no uncommitted change."""
    from colorsort.training.publishing.ship import commit

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


@pytest.mark.slow
def test_the_same_training_command_gives_the_same_weights_bit_for_bit(tmp_path):
    """The randomised camera recipe's training (its image shifts drawn in a data-loading process, its data order,
    its initial weights), three updates on two demos, run twice as the pipeline runs it (``lerobot-train`` in its
    own process, torch's threads fixed by ``stages.RUN_ENV``): the same weights, byte for byte; and another seed
    gives other weights (the test can tell)."""
    from colorsort.data.collect import collect
    from colorsort.data.config import CollectConfig

    data = tmp_path / "data"
    collect(CollectConfig(out=str(data), episodes=2, image_size=(32, 32), cameras=("snapshot",),
                          repo_id=stages.REPO_ID), progress=False, log=lambda _: None)
    recipe = get_recipe("camera-snapshot-dr", {"training.batch_size": 4})
    assert recipe.training.augment_args() and recipe.training.num_workers == 1

    def weights(out: Path, seed: int = 1000) -> bytes:
        run_dir, _ = stages.train(recipe, data, 3, seed, out)
        return (run_dir / "checkpoints" / "last" / "pretrained_model" / "model.safetensors").read_bytes()

    first = weights(tmp_path / "a")
    assert weights(tmp_path / "b") == first
    assert weights(tmp_path / "c", seed=1001) != first
