"""Shifts' training ranges (``NAME:train``): values strictly between the cell as built and level 1, drawn per
episode from its seed; the recipe and the collector that record with them refuse every held-out level."""

import numpy as np
import pytest
from helpers import exit_status, new_env

from colorsort.cli.baseline import main as baseline_main
from colorsort.cli.collect import main as collect_main
from colorsort.cli.collect import parse_args as collect_args
from colorsort.data.perturbations.late_pass import LatePass
from colorsort.data.perturbations.late_pick import LatePick
from colorsort.errors import ConfigError
from colorsort.shifts import SHIFTS, parse_shifts
from colorsort.shifts.base import between
from colorsort.training.pipeline_stages import collect_command
from colorsort.training.recipes import get_recipe

WHOLLY_HELD_OUT = {"box-shape", "novel-distractors"}  # the issue: no recipe ever sees them


def numbers(magnitude) -> list[float]:
    return [float(m) for m in (magnitude if isinstance(magnitude, tuple) else (magnitude,))
            if not isinstance(m, str)]


@pytest.mark.parametrize("name", [n for n, s in SHIFTS.items() if s.trainable])
def test_a_training_range_lies_strictly_between_the_cell_and_level_1_apart_from_every_level(name):
    shift = SHIFTS[name]
    start = numbers(between(shift.as_built, shift.magnitudes[0], 0.0))
    levels = [numbers(shift.magnitude(level)) for level in (1, 2, 3)]
    for fraction in np.random.default_rng(0).uniform(size=200):
        drawn = numbers(shift.magnitude(float(fraction)))
        for k, value in enumerate(drawn):
            low, high = sorted((start[k], levels[0][k]))
            assert low <= value <= high and all(value != level[k] for level in levels)


def test_all_train_is_every_trainable_shift_and_the_wholly_held_out_have_no_range():
    assert {s.name for s in parse_shifts("all:train")} == {n for n, s in SHIFTS.items() if s.trainable}
    assert not WHOLLY_HELD_OUT & {s.name for s in parse_shifts("all:train")}
    for name in (*WHOLLY_HELD_OUT, "action-delay"):
        with pytest.raises(ConfigError, match="has no training range"):
            parse_shifts(f"{name}:train")


def test_a_training_draw_follows_the_episodes_seed_and_stays_below_level_1_in_the_sim():
    plain, env, again = new_env(seed=0), new_env(seed=0, shift="camera-pose:train,box-mass:train"), None
    try:
        again = new_env(seed=0, shift="camera-pose:train,box-mass:train")
        fractions = []
        for seed in (1, 2, 3):
            for e in (plain, env, again):
                e.reset(seed=seed)
            drawn = env.shifts.record
            assert drawn == again.shifts.record and drawn["camera-pose"]["level"] == "train"
            fraction = drawn["camera-pose"]["fraction"]
            fractions.append(fraction)
            cam = env.mj_model.camera("sensor").id
            moved = np.linalg.norm(env.mj_data.cam_xpos[cam] - plain.mj_data.cam_xpos[cam])
            assert moved == pytest.approx(0.005 * fraction, abs=1e-6) and moved < 0.005  # level 1: 0.5 cm
            box = env.plant.pool.body[0]
            assert 0.5 <= env.mj_model.body_mass[box] < 1.0  # as built 0.5 kg, level 1 1.0 kg
        assert len(set(fractions)) == 3
    finally:
        for e in (plain, env, again):
            if e is not None:
                e.close()


@pytest.mark.parametrize("given, named", [
    ("camera-pose:2", "held-out level 2 of 'camera-pose'"), ("all:1", "held-out level 1"),
    ("box-shape:1", "'box-shape' has no training range"), ("novel-distractors:train", "has no training range")])
def test_recording_into_a_held_out_range_exits_2_naming_it(capsys, tmp_path, given, named):
    """Demos recorded, or a checkpoint chosen, under a held-out level: refused, one line each, nothing made."""
    assert exit_status(collect_main, ["--episodes", "1", "--out", str(tmp_path / "d"), "--shift", given]) == 2
    assert exit_status(baseline_main, ["--recipe", "camera-snapshot-dr", f"--demos.shift={given}",
                                       "--out", str(tmp_path / "b")]) == 2
    assert exit_status(baseline_main, ["--recipe", "camera-snapshot-touch-dr", f"--evaluation.select_shift={given}",
                                       "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and all(named in line for line in err)
    assert not any((tmp_path / name).exists() for name in "dbc")


def test_the_dr_recipe_records_every_training_range_and_its_dataset_says_so():
    recipe = get_recipe("camera-snapshot-dr")
    plain = get_recipe("camera-snapshot")
    assert {s.name for s in parse_shifts(recipe.demos.shift)} == {n for n, s in SHIFTS.items() if s.trainable} - {
        "box-size"} and recipe.label == f"{plain.label}, randomised shifts"
    command = collect_command(recipe, "default", 0, 8, 1)
    assert f"--shift={recipe.demos.shift}" in command
    assert "--shift" not in " ".join(collect_command(plain, "default", 0, 8, 1))
    assert "shift" not in plain.to_json()["demos"] and recipe.to_json()["demos"]["shift"] == recipe.demos.shift
    config = collect_args(["--shift", "camera-pose:train"])
    assert config.settings()["shift"] == "camera-pose:train"
    assert "shift" not in collect_args([]).settings()


@pytest.mark.parametrize("name", ["camera-snapshot-touch-dr", "camera-diffusion-touch-dr"])
def test_the_touch_dr_recipes_randomise_every_training_range_and_choose_their_checkpoint_under_them(name, tmp_path,
                                                                                                    monkeypatch):
    """Every shift with a training range, box-size's included (the touch-off expert sorts any size), none wholly
    held out; passes held back up to 100 steps (late_pass) and picks up to 30 (late_pick), so that a box waiting at
    a still arm is labelled go about as often as pass (docs/studies/2026-12-touch-dr-first-seed.md); the images not
    relit; each checkpoint plays its validation episodes unshifted and under the same ranges, both counted in the
    choice."""
    from pathlib import Path

    from colorsort.training import pipeline_stages as stages
    from colorsort.training.selection import validate

    recipe = get_recipe(name)
    trained = {n for n, s in SHIFTS.items() if s.trainable}
    assert {s.name for s in parse_shifts(recipe.demos.shift)} == trained and "box-size" in trained
    assert not trained & {"box-shape", "novel-distractors"}
    assert recipe.evaluation.select_shift == recipe.demos.shift and name.endswith("-dr")
    holds = {p.name: p for p in recipe.demos.perturbations}
    assert holds["late_pick"] == LatePick(30) and holds["late_pass"] == LatePass(100)
    assert not recipe.training.image_relight and "ColorJitter" not in " ".join(recipe.training.augment_args())
    calls = []

    def fake_evaluate(recipe, model, variant, episodes, stem, envs, log_dir, first_seed=None, shift=""):
        calls.append((variant, shift))
        return {"episodes": episodes, "successes": episodes if shift else 0, "correct": 0, "misplaced": 0,
                "dropped": 0, "success_rate": 1.0 if shift else 0.0}

    monkeypatch.setattr(stages, "score_policy", fake_evaluate)
    (point,) = validate(recipe, "run", [(1000, 5.0, Path("model"))], tmp_path, 1)
    variants = recipe.demos.train_variants
    assert calls == [(v, s) for v in variants for s in ("", recipe.demos.shift)]
    assert point.episodes == 2 * len(variants) * recipe.evaluation.select_episodes
    assert point.successes == len(variants) * recipe.evaluation.select_episodes  # the shifted ones count


def test_each_recorded_episode_keeps_what_its_training_ranges_drew(tmp_path):
    """``colorsort-collect --shift box-size:train,camera-pose:train``: the dataset's ``meta/colorsort.json`` holds, per
    kept episode number, each shift's level and values, those the benchmark's env draws for that seed; a resumed
    collection keeps the earlier episodes' and adds its own; a collection without shifts holds none."""
    import json

    out = tmp_path / "d"
    shift = "box-size:train,camera-pose:train"
    assert collect_main(["--episodes", "2", "--cameras", "none", "--shift", shift, "--out", str(out)]) == 0
    marker = json.loads((out / "meta" / "colorsort.json").read_text())
    assert sorted(marker["draws"]) == [str(i) for i in marker["episodes"]] == ["0", "1"]
    env = new_env(shift=shift)
    try:
        for number, drawn in marker["draws"].items():
            env.reset(seed=int(number))
            assert drawn == json.loads(json.dumps(env.shifts.record))  # as the env draws it for that seed
            assert set(drawn) == {"box-size", "camera-pose"} and 9.0 < drawn["box-size"]["edge_cm"] < 11.0
    finally:
        env.close()
    assert collect_main(["--episodes", "3", "--cameras", "none", "--shift", shift, "--out", str(out), "--resume"]) == 0
    again = json.loads((out / "meta" / "colorsort.json").read_text())
    assert sorted(again["draws"]) == ["0", "1", "2"] and again["draws"]["0"] == marker["draws"]["0"]
    plain = tmp_path / "plain"
    assert collect_main(["--episodes", "1", "--cameras", "none", "--out", str(plain)]) == 0
    assert "draws" not in json.loads((plain / "meta" / "colorsort.json").read_text())
