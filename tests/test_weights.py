"""Checkpoints stored in float16: every floating tensor rounded, the rest and the file's mode untouched, the float32
file kept beside the training state, a float32 run's copy rounded in place of a new training; checkpoints averaged
over the latest k, from lerobot-train's own weights whatever the file holds. (LeRobot's own loader taking the
halved file into its float32 model: test_pipeline's diffusion recipe in small.)"""

import json
import os

import numpy as np
import pytest
import torch
from safetensors.torch import load_file, save_file

from colorsort.training import cache
from colorsort.training import pipeline_stages as stages
from colorsort.training.recipes import get_recipe
from colorsort.training.weights import FULL, average, derived_copy, saved_every, store


def fake_run(run_dir, steps=(1, 2)):
    """A finished lerobot-train run's folders: per checkpoint a model (float32 weights, an int64 counter) and its
    training state; ``last`` linking to the final one; the timing beside the run."""
    rng = np.random.default_rng(0)
    for step in steps:
        ckpt = run_dir / "checkpoints" / f"{step:06d}"
        (ckpt / "pretrained_model").mkdir(parents=True)
        (ckpt / "training_state").mkdir()
        save_file({"w": torch.from_numpy(rng.normal(size=(4, 3)).astype(np.float32)),
                   "count": torch.tensor([step], dtype=torch.int64)}, ckpt / "pretrained_model" / "model.safetensors")
        (ckpt / "pretrained_model" / "model.safetensors").chmod(0o644)
        (ckpt / "training_state" / "training_step.json").write_text(json.dumps({"step": step}))
        os.utime(ckpt / "training_state" / "training_step.json", (1000.0 + step, 1000.0 + step))
    (run_dir / "checkpoints" / "last").symlink_to(f"{steps[-1]:06d}")
    run_dir.with_name(run_dir.name + ".json").write_text(json.dumps({"started": 900.0, "wall_s": 102.0}))


def test_storing_float16_rounds_every_floating_tensor_once_and_leaves_the_rest(tmp_path):
    run_dir = tmp_path / "run"
    fake_run(run_dir)
    before = load_file(run_dir / "checkpoints" / "000002" / "pretrained_model" / "model.safetensors")
    assert store(run_dir, "float32") == 0
    assert store(run_dir, "float16") == 2  # both checkpoints, not "last" again
    after = load_file(run_dir / "checkpoints" / "000002" / "pretrained_model" / "model.safetensors")
    assert after["w"].dtype == torch.float16 and torch.equal(after["w"], before["w"].half())
    assert after["count"].dtype == torch.int64 and after["count"].item() == 2
    assert store(run_dir, "float16") == 0  # already stored so
    kept = load_file(run_dir / "checkpoints" / "000002" / "training_state" / "model.float32.safetensors")
    assert kept["w"].dtype == torch.float32 and torch.equal(kept["w"], before["w"])  # to measure the rounding by
    stat = (run_dir / "checkpoints" / "000002" / "pretrained_model" / "model.safetensors").stat()
    assert stat.st_size < 200  # 12 weights of 2 bytes, 1 counter of 8, and the header
    assert stat.st_mode & 0o777 == 0o644


def test_a_float16_run_is_its_float32_twins_checkpoints_rounded_with_the_same_training_time(tmp_path):
    full, halved = tmp_path / "train" / "full", tmp_path / "train" / "halved"
    fake_run(full)
    timing = derived_copy(full, halved, "float16")
    assert timing == {"started": 900.0, "wall_s": 102.0, "weights_of": "full"}
    assert (halved / "checkpoints" / "last").readlink().name == "000002"
    for step in ("000001", "000002"):
        ours = load_file(halved / "checkpoints" / step / "pretrained_model" / "model.safetensors")
        theirs = load_file(full / "checkpoints" / step / "pretrained_model" / "model.safetensors")
        assert ours["w"].dtype == torch.float16 and theirs["w"].dtype == torch.float32  # the twin is kept
        assert torch.equal(ours["w"], theirs["w"].half())
        saved = halved / "checkpoints" / step / "training_state" / "training_step.json"
        assert saved.stat().st_mtime == 1000.0 + int(step)  # a checkpoint's minutes of training come from it


def test_the_weights_setting_names_its_runs_apart_and_keeps_float32_keys_as_they_were():
    """float16 gets a run folder of its own; float32 (every ACT recipe) the key it had before the setting existed."""
    preset = get_recipe("camera-diffusion")
    full = preset.override({"training.weights": "float32"})
    assert preset.training.weights == "float16" and "weights" not in stages.train_settings(full)
    assert cache.key(stages.train_settings(preset)) != cache.key(stages.train_settings(full))
    assert get_recipe("camera").training.weights == "float32"
    with pytest.raises(ValueError, match=r"weights='bfloat16': valid weights are \['float32', 'float16'\]"):
        get_recipe("camera", {"training.weights": "bfloat16"})


def weights_of(run_dir, step, name="model.safetensors"):
    folder = "pretrained_model" if name == "model.safetensors" else "training_state"
    return load_file(run_dir / "checkpoints" / f"{step:06d}" / folder / name)


def test_averaging_gives_each_checkpoint_the_mean_of_the_latest_k_of_lerobots_own_weights(tmp_path):
    run_dir = tmp_path / "run"
    fake_run(run_dir, steps=(1, 2, 3, 4))
    raw = {step: weights_of(run_dir, step)["w"] for step in (1, 2, 3, 4)}
    assert saved_every(run_dir, 2, 4) and not saved_every(run_dir, 2, 6)  # what a twin must have to be averaged
    assert average(run_dir, 1) == 0
    assert average(run_dir, 3) == 4
    assert torch.equal(weights_of(run_dir, 1)["w"], raw[1])  # the first has nothing before it
    assert torch.allclose(weights_of(run_dir, 2)["w"], (raw[1] + raw[2]) / 2)
    assert torch.allclose(weights_of(run_dir, 4)["w"], (raw[2] + raw[3] + raw[4]) / 3, atol=1e-7)
    assert weights_of(run_dir, 4)["count"].item() == 4  # counters are the checkpoint's own
    assert torch.equal(weights_of(run_dir, 4, FULL)["w"], raw[4])  # lerobot-train's file kept
    assert average(run_dir, 3) == 0  # already averaged so
    assert store(run_dir, "float16") == 4  # then rounded, still naming what it averaged
    assert torch.equal(weights_of(run_dir, 4)["w"], ((raw[2] + raw[3] + raw[4]) / 3).half())
    from safetensors import safe_open
    with safe_open(str(run_dir / "checkpoints" / "000004" / "pretrained_model" / "model.safetensors"), "pt") as f:
        assert f.metadata()["averaged"] == "000002,000003,000004"
    assert average(run_dir, 2) == 2  # another window: averaged anew from the kept files (000002's is the same)
    assert torch.allclose(weights_of(run_dir, 4)["w"], (raw[3] + raw[4]) / 2)


def test_an_averaged_run_is_copied_from_a_rounded_twin_out_of_its_float32_files(tmp_path):
    twin, averaged = tmp_path / "train" / "twin", tmp_path / "train" / "averaged"
    fake_run(twin, steps=(1, 2, 3))
    raw = {step: weights_of(twin, step)["w"] for step in (1, 2, 3)}
    store(twin, "float16")  # the shipped recipe's runs are rounded: their float32 files sit in training_state/
    timing = derived_copy(twin, averaged, "float16", 2)
    assert timing["weights_of"] == "twin"
    assert torch.equal(weights_of(averaged, 3)["w"], ((raw[2] + raw[3]) / 2).half())
    assert weights_of(twin, 3)["w"].dtype == torch.float16  # the twin untouched


def test_averaging_is_part_of_a_runs_name_with_the_spacing_of_its_checkpoints_and_needs_them():
    preset = get_recipe("camera-diffusion")
    averaged = preset.override({"training.save_every": 500, "training.average": 4})
    assert "average" not in stages.train_settings(preset)
    assert stages.train_settings(averaged)["average"] == [4, 500]
    assert cache.key(stages.train_settings(averaged)) != cache.key(stages.train_settings(
        averaged.override({"training.save_every": 1000})))
    with pytest.raises(ValueError, match="average=4 averages checkpoints saved along the run: give save_every"):
        get_recipe("camera", {"training.save_every": 0, "training.average": 4})
    with pytest.raises(ValueError, match="average=0: give at least 1"):
        get_recipe("camera", {"training.average": 0})
