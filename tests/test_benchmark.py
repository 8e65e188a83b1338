"""The benchmark: Gymnasium ids, variants, the evaluation harness, and LeRobot policies on the task."""

import json
from pathlib import Path

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from helpers import console_script, exit_status

from colorsort.benchmark.evaluate import evaluate
from colorsort.benchmark.metrics import wilson_interval
from colorsort.cli.eval import main as eval_main
from colorsort.config import BIN_COLORS, COLORS, Lighting
from colorsort.envs.gym_env import ColorSortGymEnv
from colorsort.variants import DEFAULT_GYM_ID, VARIANTS, get_variant

SMALL = dict(image_size=(32, 32), cameras=("scene", "wrist"))
# what an evaluation renders when a test reads only its outcomes: for the expert one camera (the off-screen renderer
# its own photo needs), for the random policy none
SENSOR_ONLY = dict(image_size=(32, 32), cameras=("sensor",))
NO_CAMERAS = dict(cameras=())
REPO = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("gym_id", [DEFAULT_GYM_ID] + [pytest.param(v.gym_id, marks=pytest.mark.slow)
                                                         for v in VARIANTS.values()])  # test-fast: the default id
def test_every_registered_id_passes_gymnasiums_env_checker_and_steps_in_lerobots_make_env(gym_id):
    """One build of each id: LeRobot's ``make_env`` (its synchronous vector env of ``gym.make``), Gymnasium's env
    checker on the env inside it, then LeRobot's observation preprocessing of a reset and steps to truncation."""
    from lerobot.configs.types import FeatureType
    from lerobot.envs.factory import make_env
    from lerobot.envs.utils import preprocess_observation

    from colorsort.envs.lerobot_env import ColorSortEnv

    cfg = ColorSortEnv(task=gym_id.removeprefix("colorsort/"), image_size=32, episode_length=3)
    envs = make_env(cfg, n_envs=1)["colorsort"][0]
    try:
        check_env(envs.envs[0].unwrapped, skip_render_check=False)
        obs, info = envs.envs[0].reset(seed=0)
        assert set(obs) == {"pixels", "agent_pos", "environment_state"} and "is_success" in info
        obs, _ = envs.reset(seed=[0])
        batch = preprocess_observation(obs)
        for key, feature in cfg.features.items():
            if key == "action":
                continue
            shape = tuple(batch[cfg.features_map[key]].shape[1:])
            h, w, c = feature.shape if feature.type is FeatureType.VISUAL else (None, None, None)
            assert shape == ((c, h, w) if c else feature.shape), (key, shape)  # images arrive channel-first
        assert envs.single_action_space.shape == cfg.features["action"].shape
        for _ in range(3):
            obs, _, terminated, truncated, info = envs.step(np.zeros((1, *cfg.features["action"].shape), np.float32))
        assert truncated[0] and not terminated[0]
    finally:
        envs.close()


def test_list_prints_one_variant_per_line(capsys):
    assert eval_main(["--list"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert [line.split()[0] for line in lines] == list(VARIANTS)


def test_unknown_variant_names_the_valid_ones(capsys):
    with pytest.raises(ValueError, match="Valid variants"):
        get_variant("hard")
    assert eval_main(["--variant", "hard", "--episodes", "1"]) == 2
    assert "Valid variants" in capsys.readouterr().err


@pytest.fixture(scope="module")
def expert_on_default():
    """The expert's first two episodes of `default` (seeds 10000, 10001): several tests read them."""
    return evaluate("expert", "default", episodes=2, progress=False, **SENSOR_ONLY)


@pytest.fixture(scope="module")
def random_from_seven():
    """Random actions, episodes from seed 7, in one env: the reference the repeat and env-count tests compare with."""
    return evaluate("random", "default", episodes=3, seed=7, progress=False, envs=1, **NO_CAMERAS)


def test_expert_sorts_every_box_on_default(expert_on_default):
    report = expert_on_default
    assert report.success_rate == 1.0 and report.correct == 2 * VARIANTS["default"].boxes
    assert report.misplaced == report.dropped == 0
    assert 9.0 < report.boxes_per_minute < 15.0  # a box every 4 s, the first one rides 4 s to the sensor


@pytest.mark.slow
def test_random_policy_fails_and_seeded_runs_repeat_exactly(random_from_seven):
    first = random_from_seven
    again = evaluate("random", "default", episodes=3, seed=7, progress=False, **NO_CAMERAS)
    assert first.success_rate == 0.0
    assert first.per_episode == again.per_episode and first.seeds == [7, 8, 9]


@pytest.mark.slow
def test_the_same_seeds_give_the_same_numbers_whatever_the_number_of_envs(random_from_seven, capsys):
    one = random_from_seven
    two = evaluate("random", "default", episodes=3, seed=7, progress=False, envs=2, **NO_CAMERAS)
    assert one.per_episode == two.per_episode and one.sim_time_s == two.sim_time_s
    assert eval_main(["--policy", "random", "--episodes", "2", "--seed", "7", "--envs", "2",
                      "--cameras", "none"]) == 0
    assert "success rate" in capsys.readouterr().out
    assert exit_status(eval_main, ["--episodes", "1", "--envs", "0"]) == 2
    assert "--envs (--executor.workers): workers=0 is out of range; valid values lie in [1" in capsys.readouterr().err


@pytest.mark.slow
def test_each_box_of_an_episode_says_where_it_was_set_down(expert_on_default):
    """On `jitter` the boxes lie off the centre line and turned, within the variant's ranges; on `default` on it."""
    jitter = evaluate("expert", "jitter", episodes=1, progress=False, **SENSOR_ONLY)
    plain = expert_on_default
    boxes = jitter.per_episode[0]["boxes"]
    config = VARIANTS["jitter"].task_config
    assert len(boxes) == VARIANTS["jitter"].boxes and all(b["outcome"] == "placed" for b in boxes)
    assert all(abs(b["offset"]) <= config.lateral_jitter and abs(b["yaw"]) <= config.yaw_jitter for b in boxes)
    assert len({(b["offset"], b["yaw"]) for b in boxes}) == len(boxes) and any(abs(b["yaw"]) > 1.0 for b in boxes)
    on_axis = [b for episode in plain.per_episode for b in episode["boxes"]]
    assert all(b["offset"] == 0.0 and b["yaw"] == 0.0 for b in on_axis)
    # the expert located each box, turned or not: held within 1 cm of the cup's axis, turned 10 deg at most
    held = boxes + on_axis
    assert all(b["grip_offset"] < 0.01 and abs(b["grip_yaw"]) < 10.0 for b in held)


@pytest.mark.slow
def test_distractors_are_let_through_and_counted():
    """One episode (seed 10000: 2 of its 4 boxes have no bin)."""
    report = evaluate("expert", "distractors", episodes=1, progress=False, **SENSOR_ONLY)
    assert report.success_rate == 1.0
    assert report.distractors > 0 and report.distractors_let_through == report.distractors
    assert report.correct + report.distractors_let_through == VARIANTS["distractors"].boxes


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
            assert np.allclose(m.geom_rgba[env.env.plant.pool.geom[box.index]], COLORS[box.color])
        assert np.array_equal(m.geom_rgba[bin_geoms], bins_before)
    assert not np.allclose(lights[0], lights[1])  # the lights did change
    env.close()
    assert len(bin_geoms) >= len(BIN_COLORS)


def test_a_brightness_range_changes_the_lights_brightness_alone():
    """``Variant.lighting(rng, brightness)``: the same draws, so the light colour stays the variant's."""
    variant = VARIANTS["lighting"]
    for seed in range(5):
        own, dim = (variant.lighting(np.random.default_rng(seed), b) for b in (None, (0.45, 0.75)))
        assert own.tint == dim.tint and 0.45 <= dim.brightness <= 0.75 and 0.5 <= own.brightness <= 1.6
        assert (own.brightness - 0.5) / 1.1 == pytest.approx((dim.brightness - 0.45) / 0.3)  # the same draw
    assert VARIANTS["default"].lighting(np.random.default_rng(0), (0.45, 0.75)) == Lighting()


def test_wilson_interval():
    assert wilson_interval(0, 10)[0] == 0.0 and wilson_interval(10, 10)[1] == 1.0
    lo, hi = wilson_interval(5, 10)
    assert lo < 0.5 < hi


def test_eval_cli_writes_the_json(tmp_path, capsys):
    path = tmp_path / "eval.json"
    assert eval_main(["--policy", "random", "--episodes", "1", "--image-size", "32", "--json", str(path)]) == 0
    data = json.loads(path.read_text())
    assert {"success_rate", "episodes", "correct", "misplaced", "dropped", "boxes_per_minute"} <= set(data)
    assert "success rate" in capsys.readouterr().out


def test_eval_takes_a_checkpoints_cameras_unless_told_and_refuses_others(tmp_path):
    """colorsort-eval --policy PATH renders what the checkpoint was trained on; other cameras or sizes are refused.
    The expert and random render no camera for the policy unless told (the expert takes its own sensor photos)."""
    from colorsort.benchmark.evaluate import observation_settings

    def checkpoint(name, inputs):
        path = tmp_path / name
        path.mkdir()
        (path / "config.json").write_text(json.dumps({"type": "act", "input_features": inputs}))
        return str(path)

    state = {"observation.state": {"type": "STATE", "shape": [23]},
             "observation.environment_state": {"type": "ENV", "shape": [13]}}
    state_only = checkpoint("state", state)
    vision = checkpoint("vision", {**state, "observation.images.wrist": {"type": "VISUAL", "shape": [3, 96, 96]}})
    assert observation_settings(state_only, None, None) == ((), (128, 128))
    assert observation_settings(state_only, "none", None) == ((), (128, 128))
    assert observation_settings(vision, None, None) == (("wrist",), (96, 96))
    assert observation_settings("expert", None, None) == ((), (128, 128))  # it takes its own photos
    assert observation_settings("random", None, None) == ((), (128, 128))
    assert observation_settings("expert", "sensor", 64) == (("sensor",), (64, 64))
    with pytest.raises(ValueError, match="trained on cameras"):
        observation_settings(state_only, "scene,wrist", None)
    with pytest.raises(ValueError, match="96x96"):
        observation_settings(vision, None, 128)


def test_outcomes_by_pose_counts_each_band(tmp_path):
    """``colorsort-analyze by-pose``: each box in exactly one band of |yaw| and one of offset; wrong bins and drops
    counted where they lie; the top edge (45 deg) belongs to the last band."""
    boxes = [{"outcome": "placed", "offset": -0.04, "yaw": 5.0}, {"outcome": "misplaced", "offset": 0.01, "yaw": -20.0},
             {"outcome": "misplaced", "offset": 0.03, "yaw": 45.0}, {"outcome": "dropped", "offset": 0.01, "yaw": 29.0},
             {"outcome": "let_through", "offset": 0.0, "yaw": 0.0}]
    (tmp_path / "eval.json").write_text(json.dumps({"per_episode": [{"boxes": boxes}]}))
    out = console_script("colorsort-analyze", ["by-pose", "eval.json"], tmp_path)
    assert out.returncode == 0, out.stderr
    rows = out.stdout.splitlines()[3:]
    assert rows[:3] == ["| turned 0 to 15 deg | 1 | 0 (0%) | 0 |", "| turned 15 to 30 deg | 2 | 1 (50%) | 1 |",
                        "| turned 30 to 45 deg | 1 | 1 (100%) | 0 |"]
    assert rows[3:] == ["| offset -5 to -2.5 cm | 1 | 0 (0%) | 0 |", "| offset -2.5 to 0 cm | 0 | 0 (-) | 0 |",
                        "| offset 0 to 2.5 cm | 2 | 1 (50%) | 1 |", "| offset 2.5 to 5 cm | 1 | 1 (100%) | 0 |"]


@pytest.mark.slow
def test_outcomes_by_lights_bands_episodes_by_the_lights_their_cameras_saw(tmp_path, closing):
    """``colorsort-analyze by-lights``: `lighting` seeds 10008 and 10001 fall in the dimmest and brightest bands, and
    the sensor camera sees them so (its image at 10008 under half as bright as at 10001); a mix of variants is
    refused."""
    episodes = [{"seed": 10008, "success": False, "misplaced": 0, "dropped": 1},
                {"seed": 10001, "success": True, "misplaced": 0, "dropped": 0},
                {"seed": 10001, "success": False, "misplaced": 1, "dropped": 0}]
    (tmp_path / "a.json").write_text(json.dumps({"variant": "lighting", "per_episode": episodes[:2]}))
    (tmp_path / "b.json").write_text(json.dumps({"variant": "lighting", "per_episode": episodes[2:]}))
    (tmp_path / "c.json").write_text(json.dumps({"variant": "default", "per_episode": episodes[:1]}))
    out = console_script("colorsort-analyze", ["by-lights", "a.json", "b.json"], tmp_path)
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines()[3:] == ["| brightness 0.5 to 0.65 | 1 | 0 (0%) | 0 | 1 |",
                                           "| brightness 0.65 to 0.8 | 0 | 0 (-) | 0 | 0 |",
                                           "| brightness 0.8 to 1 | 0 | 0 (-) | 0 | 0 |",
                                           "| brightness 1 to 1.6 | 2 | 1 (50%) | 1 | 0 |"]
    mixed = console_script("colorsort-analyze", ["by-lights", "a.json", "c.json"], tmp_path)
    assert mixed.returncode == 2 and "one variant" in mixed.stderr
    (tmp_path / "demos" / "meta").mkdir(parents=True)  # a collection from seed 10000 that kept episodes 1 and 8
    (tmp_path / "demos" / "meta" / "colorsort.json").write_text(json.dumps(
        {"settings": {"variant": "lighting", "seed": 10000}, "episodes": [1, 8]}))
    demos = console_script("colorsort-analyze", ["by-lights", "--demos", "demos"], tmp_path)
    assert demos.returncode == 0, demos.stderr
    first, second = map(float, demos.stdout.split("brightness: ")[1].split(", "))
    assert first >= 1.0 and 0.5 <= second < 0.65  # the bands above put these seeds in the brightest and dimmest
    env = closing(ColorSortGymEnv("lighting", cameras=("sensor",), image_size=(32, 32)))
    dim, bright = (env.reset(seed=s)[0]["pixels"]["sensor"].astype(float).mean() for s in (10008, 10001))
    assert dim < 0.5 * bright


def test_outcomes_by_pose_counts_boxes_by_how_the_cup_held_them(tmp_path):
    """With grips recorded, boxes never picked are left out of the grip bands and counted among the drops; |grip yaw|
    either way."""
    boxes = [{"outcome": "placed", "offset": 0.0, "yaw": 0.0, "grip_offset": 0.002, "grip_yaw": 1.0},
             {"outcome": "misplaced", "offset": 0.04, "yaw": 30.0, "grip_offset": 0.026, "grip_yaw": -22.0},
             {"outcome": "misplaced", "offset": 0.01, "yaw": 10.0, "grip_offset": 0.012, "grip_yaw": 8.0},
             {"outcome": "dropped", "offset": 0.0, "yaw": 0.0, "grip_offset": None, "grip_yaw": None}]
    (tmp_path / "eval.json").write_text(json.dumps({"per_episode": [{"boxes": boxes}]}))
    out = console_script("colorsort-analyze", ["by-pose", "eval.json"], tmp_path)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert "1 dropped: 1 never picked, 0 lost after the cup picked them" in lines
    assert ("how the cup held the 3 boxes it picked: gripped off axis median 12.0 mm, 90th percentile 26.0 mm; "
            "gripped turned median 8.0 deg, 90th percentile 22.0 deg") in lines
    assert lines[-8:] == ["| gripped off axis 0 to 5 mm | 1 | 0 (0%) | 0 |",
                          "| gripped off axis 5 to 10 mm | 0 | 0 (-) | 0 |",
                          "| gripped off axis 10 to 20 mm | 1 | 1 (100%) | 0 |",
                          "| gripped off axis 20 to 30 mm | 1 | 1 (100%) | 0 |",
                          "| gripped off axis 30 to 60 mm | 0 | 0 (-) | 0 |",
                          "| gripped turned 0 to 5 deg | 1 | 0 (0%) | 0 |",
                          "| gripped turned 5 to 15 deg | 1 | 1 (100%) | 0 |",
                          "| gripped turned 15 to 45 deg | 1 | 1 (100%) | 0 |"]
    lost = [*boxes, {"outcome": "dropped", "offset": 0.0, "yaw": 0.0, "grip_offset": 0.004, "grip_yaw": 2.0}]
    (tmp_path / "lost.json").write_text(json.dumps({"per_episode": [{"boxes": lost}]}))
    out = console_script("colorsort-analyze", ["by-pose", "lost.json"], tmp_path)
    assert "2 dropped: 1 never picked, 1 lost after the cup picked them" in out.stdout.splitlines()




def test_the_expert_policy_plays_with_the_settings_it_is_given(closing):
    """``ExpertPolicy(config)`` (``benchmarks/probe_descent.py --expert``) builds its expert from ``config``, not from
    the belt's preset; without one it takes the preset."""
    from colorsort.benchmark.policies import ExpertPolicy
    from colorsort.expert.config import TRACKING_EXPERT, changed

    env = closing(ColorSortGymEnv("tracking-jitter", cameras=(), render_mode="rgb_array"))
    env.reset(seed=0)
    deeper = changed(TRACKING_EXPERT, (("press", 0.01), ("track_hold_time", 0.15)))
    given, preset = ExpertPolicy(deeper), ExpertPolicy()
    given.reset(env, 0)
    preset.reset(env, 0)
    assert given.expert.config == deeper and preset.expert.config == TRACKING_EXPERT
