"""The expert takes over a cell in a state it did not make (DAgger's expert labels the states a policy reaches): the
arm somewhere else, a box dropped back on the belt, a box carried over the wrong bin; each time every box ends in the
bin of its colour."""

import numpy as np
import pytest
from helpers import exit_status, move_to
from test_expert import assert_all_in_their_bins, make_expert_env, run_until

from colorsort.cell.privileged import TakeOver, take_over_view
from colorsort.expert.factory import make_expert
from colorsort.expert.sorter import SorterPhase
from colorsort.expert.tracking import TrackingPhase


def expert_until(env, expert, obs, done, max_time: float = 20.0):
    """Step the expert until ``done(expert, obs)``; the last observation."""
    while not done(expert, obs):
        assert env.cur_time < max_time, f"the expert never reached that state (phase {expert.phase})"
        obs, _, _, _ = env.step(expert.act(obs))
    return obs


@pytest.mark.slow
def test_from_an_arm_pose_of_its_own_it_sorts_every_box(make_env):
    """A policy moved the arm to a pose the expert never takes (low over the belt's far side, wrist turned) while
    the first box rode to the sensor; the expert takes over and sorts all three."""
    env, expert, obs = make_expert_env(make_env)
    pose = expert.home + np.array([0.5, 0.35, 0.1, 0.8, -0.4, 1.2])
    obs, _ = move_to(env, pose, suction=-1.0, duration=1.5, settle=0.5)
    assert not env.suction_sealed
    expert.take_over(obs, take_over_view(env.plant))
    assert expert.phase is SorterPhase.CLEAR
    run_until(env, expert, obs, boxes=3, max_time=30.0)
    assert_all_in_their_bins(env, 3)


@pytest.mark.slow
def test_a_box_dropped_back_on_the_belt_is_picked_again(make_env):
    """The cup lets go of its box 2 cm over the belt just after the seal; the box falls back at the sensor, and
    the expert, taking over with nothing held, looks at it again, picks it and sorts every box."""
    env, expert, obs = make_expert_env(make_env)
    obs = expert_until(env, expert, obs, lambda e, _: e.phase is SorterPhase.BACK_UP)
    cup_z = float(obs["robot0_eef_pos"][2])
    obs = expert_until(env, expert, obs, lambda _, o: float(o["robot0_eef_pos"][2]) > cup_z + 0.02)
    obs, _ = move_to(env, obs["robot0_joint_pos"], suction=-1.0, duration=0.05, settle=1.0)  # let go, held still
    assert not env.suction_sealed and env.box_detected  # back at the sensor
    expert.take_over(obs, take_over_view(env.plant))
    run_until(env, expert, obs, boxes=3, max_time=35.0)
    assert_all_in_their_bins(env, 3)
    assert len(env.grips) == 4  # the dropped box was gripped twice


@pytest.mark.slow
def test_a_box_carried_over_the_wrong_bin_goes_to_the_bin_of_its_colour(make_env):
    """A policy carried the sealed box over another colour's bin; told what it holds, the expert takes it on to
    its own bin and sorts the rest."""
    env, expert, obs = make_expert_env(make_env)
    obs = expert_until(env, expert, obs, lambda e, _: e.phase is SorterPhase.MOVE_OVER_BIN)
    color = take_over_view(env.plant).held
    wrong = next(c for c in expert.q_drop if c != color)
    obs, _ = move_to(env, expert.q_drop[wrong][0], suction=1.0, duration=1.5, settle=0.3)
    assert env.suction_sealed and take_over_view(env.plant).held == color and not env.events  # over the wrong bin
    expert.take_over(obs, take_over_view(env.plant))
    assert expert.seen_color == color and expert.suction
    run_until(env, expert, obs, boxes=3, max_time=35.0)
    assert_all_in_their_bins(env, 3)


@pytest.mark.slow
def test_a_held_box_of_no_bin_colour_goes_back_onto_the_belt_at_the_sensor(make_env):
    """Told that the held box has no bin (a distractor a policy picked), the expert sets it back on the belt at the
    sensor to be looked at again: here the box is in fact red, so the next look sends it to the red bin."""
    env, expert, obs = make_expert_env(make_env)
    obs = expert_until(env, expert, obs, lambda e, _: e.phase is SorterPhase.MOVE_OVER_BIN)
    color = take_over_view(env.plant).held
    expert.take_over(obs, TakeOver("yellow", ()))
    obs = expert_until(env, expert, obs, lambda e, _: e.phase is SorterPhase.RELEASE)
    obs = expert_until(env, expert, obs, lambda e, _: e.phase is not SorterPhase.RELEASE)  # let go of it
    assert env.box_detected and not env.suction_sealed and not env.events  # on the belt at the ray, in no bin
    run_until(env, expert, obs, boxes=3, max_time=35.0)
    assert_all_in_their_bins(env, 3)
    assert env.events[0].color == color and len(env.grips) == 4


def tracking_env(make_env):
    return make_env(preset="tracking", has_offscreen_renderer=True, use_camera_obs=False, ignore_done=True)


def test_on_a_moving_belt_it_meets_the_boxes_that_passed_the_ray_before_it_took_over(make_env):
    """A policy held the arm off to the side while the first box passed the ray, unseen by the expert; taking
    over, the expert is told where that box lies (the simulator's pose, as its photo would have said) and meets it
    on the move, then every box after it: none dropped, none in a wrong bin."""
    env = tracking_env(make_env)
    obs = env.reset(seed=1)
    expert = make_expert(env)
    aside = expert.home + np.array([-0.6, 0.2, 0.0, 0.0, 0.3, 0.0])
    obs, _ = move_to(env, aside, suction=-1.0, duration=1.0, settle=0.0)
    while not take_over_view(env.plant).past_the_ray:
        obs, _ = move_to(env, aside, suction=-1.0, duration=0.05, settle=0.0)
    view = take_over_view(env.plant)
    assert len(view.past_the_ray) == 1 and not env.events
    expert.take_over(obs, view)
    assert [s.cycle.seen_color for s in expert.queue] == [view.past_the_ray[0].color]
    run_until(env, expert, obs, boxes=3, max_time=30.0)
    assert_all_in_their_bins(env, 3)
    assert expert.let_go == 0


@pytest.mark.slow
def test_on_a_moving_belt_a_box_carried_over_the_wrong_bin_goes_to_its_own(make_env):
    env = tracking_env(make_env)
    obs = env.reset(seed=1)
    expert = make_expert(env)
    expert.reset(obs)
    obs = expert_until(env, expert, obs, lambda e, _: e.phase is TrackingPhase.MOVE_OVER_BIN)
    color = take_over_view(env.plant).held
    wrong = next(c for c in expert.q_drop if c != color)
    obs, _ = move_to(env, expert.q_drop[wrong][0], suction=1.0, duration=1.0, settle=0.2)
    assert env.suction_sealed and not env.events
    expert.take_over(obs, take_over_view(env.plant))
    run_until(env, expert, obs, boxes=3, max_time=30.0)
    assert_all_in_their_bins(env, 3)


@pytest.mark.slow
@pytest.mark.parametrize("policy_steps, sealed", [(95, False), (115, True)])
def test_it_takes_over_from_a_shipped_policy_in_the_middle_of_an_episode(policy_steps, sealed):
    """The shipped camera policy acts for 4.75 s (its cup coming down onto the first box, not yet sealed) or
    5.75 s (carrying that box, sealed); the expert takes over from the state the policy left and the episode is a
    success: every box in the bin of its colour."""
    from baseline_common import SHIPPED

    from colorsort.benchmark.policies import LeRobotPolicy, checkpoint_cameras
    from colorsort.envs.gym_env import ColorSortGymEnv

    cameras, size = checkpoint_cameras(SHIPPED["act-camera"])
    assert size is not None and "sensor" in cameras  # the expert looks through the policy's own sensor camera
    env = ColorSortGymEnv("default", cameras=cameras, image_size=size)
    try:
        policy = LeRobotPolicy(SHIPPED["act-camera"])
        obs, _ = env.reset(seed=10000)
        policy.reset(env, 10000)
        for _ in range(policy_steps):
            obs, _, terminated, _, info = env.step(policy.act(obs))
            assert not terminated
        assert env.env.suction_sealed is sealed and not env.env.events
        expert = make_expert(env.env)
        expert.take_over(env.raw_obs, take_over_view(env.env.plant))
        terminated = truncated = False
        while not (terminated or truncated):
            _, _, terminated, truncated, info = env.step(expert.act(env.raw_obs).astype(np.float32))
        assert info["is_success"], info
        assert_all_in_their_bins(env.env, env.variant.boxes)
    finally:
        env.close()


@pytest.mark.slow
def test_dagger_records_the_experts_labels_from_the_states_a_policy_reached(tmp_path, monkeypatch, capsys):
    """docs/expert.md's colorsort-takeover command, as written (from a folder holding the shipped baselines): the
    shipped state policy drives each episode for 30-60 steps (drawn from the episode's seed), the expert takes over
    and finishes it: its frames from the policy's state on are a LeRobot dataset with the demos' features, their
    own task text and a record of where they came from; an existing folder is refused."""
    import json
    import shlex
    from pathlib import Path

    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from colorsort.cli.takeover import main
    from colorsort.envs.gym_env import ColorSortGymEnv
    from colorsort.envs.schema import STATE
    from colorsort.training.takeover import PROVENANCE, TAKEOVER_SEED, TAKEOVER_TASK, TakeoverConfig, handover_step

    repo = Path(__file__).resolve().parents[1]
    (line,) = [ln for ln in (repo / "docs" / "expert.md").read_text().splitlines()
               if ln.startswith("colorsort-takeover ")]
    argv = shlex.split(line)[1:]
    (tmp_path / "baselines").symlink_to(repo / "baselines")
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 0
    out = tmp_path / "datasets" / "labels"
    assert "kept 2 of 2 episodes" in capsys.readouterr().out
    provenance = json.loads((out / "meta" / PROVENANCE).read_text())
    seeds = [TAKEOVER_SEED, TAKEOVER_SEED + 1]
    assert provenance["policy"] == "baselines/act-state" and provenance["kept"] == seeds
    assert provenance["handed_over_at"] == {str(s): handover_step(s, (30, 60)) for s in seeds}
    assert all(30 <= n <= 60 for n in provenance["handed_over_at"].values())
    dataset = LeRobotDataset("local/colorsort-takeover", root=out)
    assert dataset.num_episodes == 2
    assert list(dataset.meta.tasks.index) == [TAKEOVER_TASK]
    assert "observation.environment_state" in dataset.meta.features and not dataset.meta.video_keys

    # the first labelled frame is the state the policy left, not the reset's: the arm has moved
    reset = ColorSortGymEnv("default", cameras=(), render_mode=None)
    try:
        start = reset.reset(seed=seeds[0])[0]["agent_pos"]
    finally:
        reset.close()
    first = dataset[0][STATE].numpy()
    assert np.abs(first[:6] - start[:6]).max() > 0.05  # [rad]
    assert main(argv) == 2 and "never overwritten" in capsys.readouterr().err
    with pytest.raises(ValueError, match="handover"):
        TakeoverConfig(policy="p", out="o", handover=(60, 30))


def test_the_expert_that_takes_over_is_the_one_that_made_the_demos():
    """``--expert`` (``TakeoverConfig.expert``) changes the taking-over expert's settings from its belt's preset, as
    colorsort-collect's does the demos', and ``--no-turn`` keeps its home yaw; a name it cannot change is refused
    naming the valid ones."""
    from colorsort.cli.takeover import main
    from colorsort.expert.config import TRACKING_EXPERT
    from colorsort.training.takeover import TakeoverConfig

    deeper = TakeoverConfig(policy="p", out="o", variant="tracking-jitter", expert=(("press", 0.01),))
    assert deeper.expert_config.press == 0.01
    assert deeper.expert_config.touch_speed == TRACKING_EXPERT.touch_speed
    assert TakeoverConfig(policy="p", out="o", variant="tracking").expert_config == TRACKING_EXPERT
    with pytest.raises(ValueError, match="valid names: .*'press'"):
        TakeoverConfig(policy="p", out="o", expert=(("hold", 0.15),))
    assert exit_status(main, ["--policy", "p", "--out", "o", "--expert", "press"]) == 2
    still = TakeoverConfig(policy="p", out="o", variant="jitter", turn_to_box=False)  # --no-turn
    assert not still.expert_config.turn_to_box and TakeoverConfig(policy="p", out="o").expert_config.turn_to_box
