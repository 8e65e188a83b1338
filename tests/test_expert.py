"""The scripted expert sorts by what its camera sees, waits for the sensor, lets unknown boxes through."""

import json
from dataclasses import replace

import numpy as np
import pytest
from helpers import TOUCH_STYLES, exit_status

from colorsort.cli.sort import main as sort_main
from colorsort.expert.config import STOPPING_EXPERT
from colorsort.expert.factory import make_expert
from colorsort.expert.planning import site_yaw
from colorsort.expert.sorter import SorterPhase


def make_expert_env(make_env, robot="IRB140", config=None, **kwargs):
    env = make_env(robot, has_offscreen_renderer=True, use_camera_obs=True, camera_names=["sensor"], **kwargs)
    obs = env.reset()
    expert = make_expert(env, config)
    expert.reset(obs)
    return env, expert, obs


def run_until(env, expert, obs, boxes: int, max_time: float, on_step=None):
    while len(env.events) < boxes and env.cur_time < max_time:
        action = expert.act(obs)
        obs, _, _, info = env.step(action)
        if on_step is not None:
            on_step(action, obs, info)
    return obs


def assert_all_in_their_bins(env, boxes):
    assert len(env.events) >= boxes
    for event in env.events[:boxes]:
        assert event.outcome == "placed" and event.bin == event.color
    assert env.tally.misplaced == 0 and env.tally.dropped == 0


@pytest.mark.slow
def test_sorts_three_boxes_into_the_right_bins(make_env):
    env, expert, obs = make_expert_env(make_env)
    run_until(env, expert, obs, boxes=3, max_time=25.0)
    assert_all_in_their_bins(env, 3)
    assert [c.seen_color for c in expert.cycles[:3]] == [e.color for e in env.events[:3]]


def test_picks_off_centre_turned_boxes(make_env):
    env, expert, obs = make_expert_env(make_env, lateral_jitter=0.05, yaw_jitter=45.0, seed=4)
    run_until(env, expert, obs, boxes=3, max_time=25.0)
    assert_all_in_their_bins(env, 3)


@pytest.mark.parametrize("turn", [True, False])
def test_turns_the_cup_to_a_turned_box_only_when_asked(turn, make_env):
    config = replace(STOPPING_EXPERT, turn_to_box=turn)
    env, expert, obs = make_expert_env(make_env, config=config, lateral_jitter=0.05, yaw_jitter=45.0, seed=4)
    picks = {}  # by identity: each pick planned, in order
    run_until(env, expert, obs, boxes=3, max_time=25.0,
              on_step=lambda a, o, i: picks.setdefault(id(expert.pick), expert.pick))
    assert_all_in_their_bins(env, 3)
    box_yaws = np.deg2rad([p.yaw for p in env.placements[:3]])
    planned = [p for p in picks.values() if p is not None][:3]
    cup_turns = [site_yaw(expert.ik.cup_pose(p.above)[1]) - expert.cup_yaw for p in planned]
    quarter = lambda a: (np.asarray(a) + np.pi / 4) % (np.pi / 2) - np.pi / 4  # noqa: E731 - a cube's yaw
    assert np.abs(quarter(box_yaws)).max() > np.deg2rad(15)  # the boxes were turned
    want = quarter(box_yaws) if turn else np.zeros(3)
    np.testing.assert_allclose(quarter(np.subtract(cup_turns, want)), 0, atol=np.deg2rad(3))


@pytest.mark.parametrize("name", list(TOUCH_STYLES))
def test_touches_off_boxes_of_any_height_it_does_not_know(name, make_env):
    """Cubes from 5 to 15 cm and a puck, the expert told none of their heights: each sealed where its top is,
    lifted and sorted, the cup's reference never more than 5 mm into a box (up to 3.1 mm at 0.12 m/s: it stops
    at the step the vacuum switch reports the seal, at most 6 mm on)."""
    style = TOUCH_STYLES[name]
    env = make_env(has_offscreen_renderer=True, use_camera_obs=True, camera_names=["sensor"], seed=1)
    env.plant.pool.style = style
    obs = env.reset()
    expert = make_expert(env)
    expert.reset(obs)
    top = env.layout.belt_top_z + style.height
    lowest = []  # the reference's cup height [m] while it comes down onto a box and stops

    def on_step(action, obs, info):
        if expert.phase in (SorterPhase.DESCEND, SorterPhase.BACK_UP):
            lowest.append(expert.ik.cup_pose(expert._current_state()[0])[0][2])

    run_until(env, expert, obs, boxes=2, max_time=16.0, on_step=on_step)
    assert_all_in_their_bins(env, 2)
    assert expert.misses == []
    assert top - 0.005 <= min(lowest) < top + 0.005


def test_a_box_gone_from_under_the_cup_ends_in_a_back_off(make_env):
    """The box taken away once the expert looked: it comes down to its floor, backs off saying why, and waits for
    the next box instead of stalling."""
    env, expert, obs = make_expert_env(make_env, seed=1, spawn_period=100.0)
    phases = []
    removed = False
    while env.cur_time < 20.0 and not (removed and expert.phase is SorterPhase.WAIT_FOR_BOX):
        obs, *_ = env.step(expert.act(obs))
        phases.append(expert.phase)
        if expert.phase is SorterPhase.DESCEND and not removed:
            for box in env.plant.pool.in_play():
                env.plant.remove_box(box)
            removed = True
    assert removed and expert.phase is SorterPhase.WAIT_FOR_BOX
    assert SorterPhase.BACK_OFF in phases and len(expert.misses) == 1 and "no seal" in expert.misses[0][1]
    cup_z = expert.ik.cup_pose(np.asarray(obs["robot0_joint_pos"]))[0][2]
    assert cup_z > env.layout.belt_top_z + env.layout.tallest_box  # up and away
    assert not expert.cycles and env.tally.dropped == 0


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["Panda", "UR5e"])
def test_sorts_with_robosuite_arms(robot, make_env):
    env, expert, obs = make_expert_env(make_env, robot)
    run_until(env, expert, obs, boxes=2, max_time=20.0)
    assert_all_in_their_bins(env, 2)


def test_does_not_pick_while_the_belt_runs_with_no_box_at_the_sensor(make_env):
    env, expert, obs = make_expert_env(make_env, spawn_period=100.0)
    seen = []

    def check(action, obs, info):
        if not any(seen) and not info["box_detected"]:  # the box still rides toward the sensor: the arm waits
            assert info["belt_running"]
            assert expert.phase in (SorterPhase.MOVE_TO_WAIT, SorterPhase.WAIT_FOR_BOX)
            assert action[-2] < 0
        seen.append(info["box_detected"])

    run_until(env, expert, obs, boxes=1, max_time=12.0, on_step=check)
    assert any(seen) and not all(seen)
    assert_all_in_their_bins(env, 1)


def test_lets_boxes_without_a_bin_ride_past_as_rejected(make_env):
    env, expert, obs = make_expert_env(make_env, box_colors=("yellow", "purple"), spawn_period=3.0)
    suction = []
    run_until(env, expert, obs, boxes=2, max_time=20.0, on_step=lambda a, o, i: suction.append(a[-2] > 0))
    assert env.tally.rejected == 2 and env.tally.dropped == 0 and not any(suction)
    assert [c.seen_color for c in expert.cycles[:2]] == ["unknown", "unknown"]


def test_seed_preset_sorts_at_the_original_rhythm(make_env):
    env, expert, obs = make_expert_env(make_env, preset="seed")
    run_until(env, expert, obs, boxes=1, max_time=30.0)
    assert_all_in_their_bins(env, 1)
    # 0.82 m of belt at 0.05 m/s: the first box reaches the sensor after about 16 s.
    assert 15.0 < expert.cycles[0].detected_at < 18.0


def test_expert_needs_the_sensor_camera(make_env):
    env = make_env()
    env.reset()
    with pytest.raises(ValueError, match="sensor camera"):
        make_expert(env)


def test_sort_cli_writes_the_summary(tmp_path, capsys):
    path = tmp_path / "sort.json"
    assert sort_main(["--boxes", "2", "--seed", "1", "--json", str(path)]) == 0
    summary = json.loads(path.read_text())
    assert {"correct", "misplaced", "dropped", "rejected", "boxes_per_minute", "boxes"} <= set(summary)
    assert summary["correct"] == 2 and len(summary["boxes"]) == 2 and summary["boxes_per_minute"] > 0
    for box in summary["boxes"]:
        assert set(box) == {"true_color", "seen_color", "bin", "cycle_time_s"}
        assert box["true_color"] == box["seen_color"] == box["bin"]
    assert "correct 2" in capsys.readouterr().out


@pytest.mark.parametrize("argv", [["--boxes", "0"], ["--robot", "Sawyer"], ["--preset", "turbo"]])
def test_sort_cli_bad_arguments_exit_2(argv, capsys):
    assert exit_status(sort_main, argv) == 2
    assert "error" in capsys.readouterr().err


@pytest.mark.parametrize("kwargs,name", [
    (dict(carry_z=2.0), "carry_z"), (dict(drop_slots=0), "drop_slots"), (dict(wait_tolerance=0.0), "wait_tolerance"),
    (dict(touch_speed=0.0), "touch_speed"), (dict(drop_spread=1.5), "drop_spread"),
])
def test_expert_config_refuses_values_out_of_range_naming_them(kwargs, name):
    from colorsort.expert.config import ExpertConfig

    with pytest.raises(ValueError, match=rf"{name}=.* valid values lie in"):
        ExpertConfig(**kwargs)


def test_the_expert_is_built_from_a_calibration_not_the_env(make_env):
    from colorsort.expert.calibration import Calibration

    env, expert, _ = make_expert_env(make_env)
    cal = expert.calibration
    assert isinstance(cal, Calibration) and not hasattr(expert, "env")
    assert np.array_equal(cal.home, env.robot_spec.home) and cal.control_period == env.control_timestep
    assert cal.camera.width == 128 and cal.kinematics.nq == len(env.robot_spec.home)


def test_the_stopping_belt_expert_sorts_as_it_always_has(tmp_path):
    """`colorsort-sort --preset default --boxes 6 --seed 0 --json`, against the summary recorded with expert version 2
    (the touch-off; tests/data): the same boxes, bins, phase times and cycle times."""
    from pathlib import Path

    path = tmp_path / "sort.json"
    assert sort_main(["--preset", "default", "--boxes", "6", "--seed", "0", "--json", str(path)]) == 0
    recorded = json.loads((Path(__file__).parent / "data" / "sort_default_6boxes_seed0.json").read_text())
    now = json.loads(path.read_text())

    def rounded(x):
        if isinstance(x, float):
            return round(x, 6)
        if isinstance(x, dict):
            return {k: rounded(v) for k, v in x.items()}
        if isinstance(x, list):
            return [rounded(v) for v in x]
        return x

    assert rounded(now) == rounded(recorded)


def test_the_teach_step_is_deterministic_and_gave_the_shipped_classes():
    """Run here, not beside a long-lived env: its own env's renderer, closed, leaves no other current."""
    from colorsort.expert.colour_classes import TaughtColours
    from colorsort.expert.teach import teach

    once, twice = teach(), teach()
    assert once == twice
    assert TaughtColours.from_json(once.to_json()) == TaughtColours.load()
