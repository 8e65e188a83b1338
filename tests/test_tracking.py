"""Conveyor tracking: a belt that never stops, its encoder, and the expert picking moving boxes."""

import numpy as np
import pytest
from helpers import TOUCH_STYLES

from colorsort.config import BIN_COLORS
from colorsort.expert.base import Cycle
from colorsort.expert.config import TRACKING_EXPERT, changed
from colorsort.expert.factory import make_expert
from colorsort.expert.tracking import Sighting, TrackingExpert
from colorsort.variants import get_variant


def tracking_env(make_env, robot: str = "IRB140", **overrides):
    return make_env(robot, preset="tracking", has_offscreen_renderer=True, use_camera_obs=False, **overrides)


def test_the_belt_never_stops_while_boxes_pass_the_ray_and_the_encoder_counts_belt_speed_times_time(make_env):
    env = tracking_env(make_env, ignore_done=True)
    obs = env.reset(seed=0)
    hold = np.concatenate([env.robot_spec.home, [-1.0, -1.0]])
    blocked = running = 0
    for _ in range(300):  # 15 s: four boxes cross the ray and ride off the end
        obs, _, _, info = env.step(hold)
        blocked += info["box_detected"]
        running += info["belt_running"]
    assert blocked > 10 and running == 300
    assert float(obs["belt_travel"]) == pytest.approx(env.config.belt_speed * env.cur_time, rel=1e-9)
    assert env.tally.dropped >= 3 and env.tally.placed == {"red": 0, "green": 0, "blue": 0}  # nobody picked them


@pytest.mark.parametrize("robot", ["IRB140", "UR5e"])
def test_the_tracking_expert_picks_moving_boxes_and_places_them_in_their_bins(robot, make_env):
    env = tracking_env(make_env, robot=robot, ignore_done=True)
    obs = env.reset(seed=1)
    expert = make_expert(env)
    assert isinstance(expert, TrackingExpert)
    expert.reset(obs)
    belt_stopped = 0
    while len(env.events) < 4 and env.cur_time < 30.0:
        obs, _, _, info = env.step(expert.act(obs))
        belt_stopped += not info["belt_running"]
    assert [e.outcome for e in env.events[:4]] == ["placed"] * 4, env.events
    assert belt_stopped == 0 and expert.let_go == 0
    assert env.events[3].time < 4 * env.config.spawn_period + 5.0  # it keeps pace with the spawner


def test_a_longer_hold_keeps_the_sealed_box_on_the_moving_belt_for_it_and_every_box_still_lands(make_env):
    """The expert's ``track_hold_time`` and ``press``, changed from the preset as ``--expert`` changes them, are
    what the cup does: sealed, it lifts each box off the moving belt at once with the preset (at most one control
    step on the belt) and holds it there for three or more with a 0.15 s hold pressing 10 mm, and both place every
    box in its bin."""
    held_on_belt = {}
    for hold, press in ((TRACKING_EXPERT.track_hold_time, TRACKING_EXPERT.press), (0.15, 0.01)):
        env = tracking_env(make_env, ignore_done=True)
        obs = env.reset(seed=1)
        expert = make_expert(env, changed(TRACKING_EXPERT, (("press", press), ("track_hold_time", hold))))
        expert.reset(obs)
        seal, data, layout = env.plant.seal, env.plant.data, env.layout
        steps = 0
        while len(env.events) < 2 and env.cur_time < 20.0:
            obs, _, _, _ = env.step(expert.act(obs))
            resting = layout.belt_top_z + layout.box_size / 2 + 0.002  # [m] a box's centre on the belt
            steps += seal.held is not None and data.xpos[seal.box_bodies[seal.held]][2] < resting
        assert [e.outcome for e in env.events[:2]] == ["placed"] * 2, env.events
        held_on_belt[hold] = steps / 2
    assert held_on_belt[TRACKING_EXPERT.track_hold_time] <= 1 and held_on_belt[0.15] >= 3


@pytest.mark.parametrize("name", list(TOUCH_STYLES))
def test_touches_off_moving_boxes_of_any_height_it_does_not_know(name, make_env):
    """On the never-stopping belt, cubes from 5 to 15 cm and a puck, the expert told none of their heights: each
    sealed where its top is, moving with it, lifted and sorted, the cup's reference never more than 5 mm into a box
    (up to 3.1 mm at 0.16 m/s: the lift starts from where the seal formed)."""
    from colorsort.expert.tracking import TrackingPhase

    style = TOUCH_STYLES[name]
    env = tracking_env(make_env, ignore_done=True, seed=1)
    env.plant.pool.style = style
    obs = env.reset()
    expert = make_expert(env)
    expert.reset(obs)
    top = env.layout.belt_top_z + style.height
    lowest = []
    while len(env.events) < 2 and env.cur_time < 12.0:
        obs, *_ = env.step(expert.act(obs))
        if expert.phase in (TrackingPhase.TRACK, TrackingPhase.LIFT):
            lowest.append(expert.ik.cup_pose(expert._current_state()[0])[0][2])
    assert [(str(e.outcome), e.bin) for e in env.events[:2]] == [("placed", e.color) for e in env.events[:2]]
    assert len(env.events) == 2 and expert.misses == [] and expert.let_go == 0
    assert top - 0.005 <= min(lowest) < top + 0.005


def test_a_box_gone_from_under_the_moving_cup_is_let_go_with_the_reason(make_env):
    """The box taken away as the touch-off starts: the cup comes down to where it gives up, says why, counts the box
    let go and goes back to meet the next one."""
    from colorsort.expert.tracking import TrackingPhase

    env = tracking_env(make_env, ignore_done=True, seed=1)
    obs = env.reset()
    expert = make_expert(env)
    expert.reset(obs)
    removed = False
    while env.cur_time < 10.0 and not (removed and expert.phase is TrackingPhase.MOVE_TO_WAIT):
        obs, *_ = env.step(expert.act(obs))
        if expert.phase is TrackingPhase.TRACK and not removed:
            env.plant.remove_box(min(env.plant.pool.in_play(), key=lambda b: env.plant.pool.pos(b)[0]))
            removed = True
    assert removed and expert.phase is TrackingPhase.MOVE_TO_WAIT
    assert expert.let_go == 1 and len(expert.misses) == 1 and "no seal" in expert.misses[0][1]
    while len(env.events) < 1 and env.cur_time < 16.0:  # and the next box is sorted
        obs, *_ = env.step(expert.act(obs))
    assert [str(e.outcome) for e in env.events] == ["placed"]


def test_a_smaller_drop_spread_lets_go_nearer_each_bins_centre_and_every_box_still_lands(make_env):
    """``drop_spread`` draws the release points in toward each bin's centre: the cup lets go up to 150 mm from
    it with the preset (its quickest slots lie toward a corner on the bin's near side), within 50 mm at 0.25 of
    the room, and both place every box in its bin."""
    farthest = {}
    for spread in (TRACKING_EXPERT.drop_spread, 0.25):
        env = tracking_env(make_env, ignore_done=True)
        obs = env.reset(seed=1)
        expert = make_expert(env, changed(TRACKING_EXPERT, (("drop_spread", spread),)))
        expert.reset(obs)
        seal, data, layout = env.plant.seal, env.plant.data, env.layout
        off, before = [], None
        while len(env.events) < 3 and env.cur_time < 25.0:
            obs, _, _, _ = env.step(expert.act(obs))
            held = env.boxes[seal.held] if seal.held is not None else None
            if before is not None and held is not before:  # let go: the cup from the centre of the box's bin
                centre = layout.bin_center(BIN_COLORS.index(before.color))
                off.append(float(np.hypot(*(data.xpos[seal.cup][:2] - centre))))
            before = held
        assert [e.outcome for e in env.events[:3]] == ["placed"] * 3, env.events
        assert len(off) >= 3
        farthest[spread] = max(off)
    assert farthest[TRACKING_EXPERT.drop_spread] > 0.12 and farthest[0.25] < 0.05, farthest


def test_a_box_the_arm_can_no_longer_meet_is_let_go_and_counted_as_dropped(make_env):
    env = tracking_env(make_env, ignore_done=True, spawn_period=600.0)  # one box, spawned at reset, rides far upstream
    obs = env.reset(seed=2)
    expert = make_expert(env)
    expert.reset(obs)
    obs, _, _, _ = env.step(expert.act(obs))
    lo, _ = expert.window
    late = env.put_box("red", lo + 0.04, env.layout.belt_y)  # in reach, but too near the end to follow down and up
    obs, serial = env.observe(), late.serial
    cycle = Cycle("red", expert.time, target_bin="red")
    expert.cycles.append(cycle)
    expert.queue.append(Sighting(cycle, float(env.box_pos(late)[0]), env.layout.belt_y, expert.cup_yaw,
                                 float(obs["belt_travel"])))
    suction = []
    while late.status.value == "in_play" and env.cur_time < 10.0:
        action = expert.act(obs)
        suction.append(action[-2] > 0)
        obs, _, _, _ = env.step(action)
    assert expert.let_go == 1 and cycle.target_bin is None and not any(suction)
    assert [(e.serial, str(e.outcome)) for e in env.events] == [(serial, "dropped")] and env.tally.dropped == 1


@pytest.mark.slow
def test_a_tracking_episode_replays_bit_for_bit(tmp_path):
    from colorsort.data.collect import collect
    from colorsort.data.config import CollectConfig
    from colorsort.data.replay import replay

    out = tmp_path / "tracking"
    summary = collect(CollectConfig(episodes=1, boxes_per_episode=2, preset="tracking", cameras=(), out=str(out)),
                      progress=False, log=lambda _: None)
    assert summary.kept == 1
    report = replay(out, 0, camera="scene", size=(32, 32), progress=False)
    assert report.state_mismatches == 0 and report.max_state_error == 0.0
    assert report.outcomes == ["placed", "placed"] and report.action_replay_ok


def test_tracking_observation_state_ends_with_the_encoder(make_env):
    from colorsort.envs.schema import robot_state, state_names, state_size

    env = tracking_env(make_env)
    obs = env.reset(seed=0)
    for _ in range(10):
        obs, _, _, _ = env.step(np.concatenate([env.robot_spec.home, [-1.0, -1.0]]))
    names = state_names(env)
    assert names[-1] == "belt.travel" and len(names) == state_size(6, tracking=True) == state_size(6) + 1
    assert robot_state(env, obs)[-1] == pytest.approx(0.2 * 0.5, rel=1e-6)  # 0.2 m/s for 0.5 s


def test_the_cup_seals_and_lifts_a_box_moving_under_it_at_belt_speed():
    """The seal trial (``benchmarks/bench_seal.py``'s): the cup held still, the box riding under it at 0.2 m/s (what
    the expert meets if it did not match the belt at all) and at 0.5 m/s (the fastest belt)."""
    from studies.seal_trial import trial

    for speed, max_offset_mm in ((0.2, 25.0), (0.5, 45.0)):
        r = trial(speed)
        assert r["sealed"] and r["held"] and r["lifted"], r
        assert r["offset_mm"] < max_offset_mm and r["turn_deg"] < 2.0, r


def test_tracking_variants_give_the_encoder_to_gymnasium_and_lerobot(closing):
    import gymnasium as gym

    from colorsort.envs.lerobot_env import ColorSortEnv

    env = closing(gym.make("colorsort/ColorSort-Tracking-v0", cameras=()))
    obs, _ = env.reset(seed=0)
    assert obs["agent_pos"].shape == (24,) == env.observation_space["agent_pos"].shape
    obs, *_ = env.step(env.action_space.sample())
    assert obs["agent_pos"][-1] == pytest.approx(0.2 * 0.05, rel=1e-5)  # the encoder after one 50 ms step
    assert ColorSortEnv(task="ColorSort-Tracking-v0").features["agent_pos"].shape == (24,)
    assert ColorSortEnv(task="ColorSort-v0").features["agent_pos"].shape == (23,)


@pytest.mark.slow
def test_colorsort_sort_reports_how_long_the_belt_stood_still(tmp_path, capsys):
    import json

    from colorsort.cli.sort import main as sort_main

    for preset in ("tracking", "default"):
        out = tmp_path / f"{preset}.json"
        assert sort_main(["--preset", preset, "--boxes", "3", "--seed", "0", "--json", str(out)]) == 0
        report = json.loads(out.read_text())
        assert report["correct"] == 3 and report["dropped"] == 0 and report["let_go"] == 0
        if preset == "tracking":
            assert report["belt_stopped_s"] == 0.0 and report["phase_seconds"]["track box"] > 0
        else:  # the belt waits while the arm picks each box
            assert report["belt_stopped_s"] > 3 * 0.5
    assert "belt stood still 0.0 s" in capsys.readouterr().out


def test_the_expert_takes_its_own_photo_whatever_size_the_recorded_sensor_camera_is(make_env):
    """A dataset's `sensor` camera at 32 px: the expert still locates each box on its own 128 px photo and places
    every box of a jittered tracking episode (on the 32 px image it dropped them all: seed 1000000, the first
    seed of a recipe's tracking-jitter demos)."""
    env = make_env(config=get_variant("tracking-jitter").task_config, has_offscreen_renderer=True, use_camera_obs=True,
                   camera_names=["sensor"], camera_heights=32, camera_widths=32)
    obs = env.reset(seed=1_000_000)
    assert obs["sensor_image"].shape[:2] == (32, 32)
    expert = make_expert(env)
    expert.reset(obs)
    while len(env.events) < 3 and env.cur_time < 20.0:
        obs, *_ = env.step(expert.act(obs))
    assert [str(e.outcome) for e in env.events[:3]] == ["placed"] * 3, env.events
    assert all(e.bin == e.color for e in env.events[:3]) and expert.let_go == 0


@pytest.mark.slow
def test_the_fast_tracking_belt_is_solved_every_box_placed_none_dropped(make_env):
    """tracking-fast (0.3 m/s, a box every 2 s): 12 boxes, every one in the bin of its colour, none let go,
    the belt never stopping, after the first one placed at the belt's rate (a box every 2.1 s or less; falling
    behind it would drop boxes); benchmarks/bench_tracking.py runs 10 seeds of 20."""
    env = make_env(preset="tracking-fast", has_offscreen_renderer=True, ignore_done=True, seed=7)
    obs = env.reset()
    expert = make_expert(env)
    expert.reset(obs)
    belt_stopped, boxes = 0, 12
    while len(env.events) < boxes and env.cur_time < 60.0:
        obs, _, _, info = env.step(expert.act(obs))
        belt_stopped += not info["belt_running"]
    assert [str(e.outcome) for e in env.events[:boxes]] == ["placed"] * boxes, env.events
    assert all(e.bin == e.color for e in env.events[:boxes])
    assert belt_stopped == 0 and expert.let_go == 0
    assert (env.events[boxes - 1].time - env.events[0].time) / (boxes - 1) <= 2.1


def test_the_legs_follow_on_without_a_pause_and_the_carry_leaves_halfway_up_clear_of_the_rails(make_env):
    """The touch-off starts where and when the interception ends, the lift from the reference's state at the seal, the
    carry halfway up the lift from the lift's state there (between control steps, not at the next one); the box,
    still rising, touches no rail (contacts read after every control step); the box is let go at the first control
    step after the carry's end (the acceleration feed-forward keeps the arm on its reference: it arrives with it,
    not settling after it)."""
    import mujoco

    from colorsort.expert.config import TRACKING_EXPERT
    from colorsort.expert.planning import DensePath, JointTrajectory
    from colorsort.expert.tracking import TrackingPhase

    env = make_env(preset="tracking-fast", has_offscreen_renderer=True, ignore_done=True, seed=3)
    obs = env.reset()
    expert = make_expert(env)
    assert isinstance(expert, TrackingExpert)
    cfg = TRACKING_EXPERT
    assert expert.carry_from == pytest.approx(cfg.track_hold_time + cfg.track_lift_time / 2)
    m, d = env.mj_model, env.mj_data
    rails = {g for g in range(m.ngeom) if (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or "").endswith(
        ("rail_left", "rail_right"))}
    assert len(rails) == 2
    expert.reset(obs)
    tracks = lifts = carries = releases = rail_contacts = 0
    while len(env.events) < 4 and env.cur_time < 30.0:
        before, now, carrying = expert.motion, expert.time, expert.phase is TrackingPhase.MOVE_OVER_BIN
        obs, *_ = env.step(expert.act(obs))
        rail_contacts += sum(d.contact[i].geom1 in rails or d.contact[i].geom2 in rails for i in range(d.ncon))
        if carrying and not expert.suction:  # let go
            releases += 1
            assert before.end <= now < before.end + expert.dt
        motion = expert.motion
        if motion is before:
            continue
        if expert.phase is TrackingPhase.TRACK:
            tracks += 1
            assert motion.started == pytest.approx(before.end) and now < motion.started <= now + expert.dt + 1e-9
        elif expert.phase is TrackingPhase.LIFT:
            lifts += 1
            assert motion.started == now
            np.testing.assert_allclose(motion.sample(now)[0], before.sample(now)[0], atol=1e-9)
        elif expert.phase is TrackingPhase.MOVE_OVER_BIN:
            carries += 1
            path = before.trajectory
            assert isinstance(path, DensePath) and isinstance(motion.trajectory, JointTrajectory)
            assert motion.started == pytest.approx(before.started + expert.carry_from)
            q, qd, _ = motion.trajectory.sample(0.0)
            np.testing.assert_allclose(q, path.sample(expert.carry_from)[0], atol=1e-9)
            np.testing.assert_allclose(qd, path.slope(expert.carry_from), atol=1e-9)
            assert path.slope(expert.carry_from)[1] != 0.0  # the lift was still moving when the carry took over
    assert [str(e.outcome) for e in env.events] == ["placed"] * 4
    assert tracks == lifts == carries == releases == 4 and rail_contacts == 0


def test_the_wait_in_an_interception_is_its_duration_beyond_the_time_optimal_plan():
    """An approach told to take 0.5 s longer than it needs (the box not yet within reach) waited 0.5 s; one
    planned time-optimally, from a moving start to a moving goal, waited nothing."""
    from studies.cycle_bound import waiting_time

    from colorsort.expert.planning import JointLimits, MotionConfig, plan_motion

    limits = JointLimits.of(np.full(6, 3.0), MotionConfig())
    start, goal = np.zeros(6), np.array([0.6, -0.3, 0.2, 0.0, 0.4, -0.5])
    moving = np.array([0.05, 0.0, -0.02, 0.0, 0.0, 0.01])  # [rad/s]
    fastest = plan_motion(start, goal, limits, start_velocity=moving, goal_velocity=moving)
    assert waiting_time(fastest, limits) == pytest.approx(0.0, abs=1e-6)
    slow = plan_motion(start, goal, limits, start_velocity=moving, goal_velocity=moving,
                       minimum_duration=fastest.duration + 0.5)
    assert slow.duration == pytest.approx(fastest.duration + 0.5)
    assert waiting_time(slow, limits) == pytest.approx(0.5, abs=1e-6)


def test_the_jerk_limited_time_from_rest_is_the_s_curves_by_hand():
    """From rest at jerk j: d = j t^3 / 6 while the acceleration climbs; past the S-curve to vmax (a/j + vmax/a
    long, covered at vmax/2 on average) d/vmax + (a/j + vmax/a)/2, which is time_to_stop's d/vmax + vmax/(2a)
    plus half a jerk ramp; a climb too short to reach a peaks at sqrt(vmax j)."""
    from studies.cycle_bound import distance_from_rest, time_from_rest, time_to_stop

    v, a, j = np.array([3.0, 6.0]), 15.0, 150.0
    assert distance_from_rest(0.05, 3.0, a, j) == pytest.approx(j * 0.05**3 / 6)
    short = np.array([0.02, 0.001])
    assert time_from_rest(short, v, a, j) == pytest.approx((6 * short / j) ** (1 / 3), abs=2e-6)
    far = np.array([2.0, 5.0])
    assert time_from_rest(far, v, a, j) == pytest.approx(far / v + (a / j + v / a) / 2, abs=2e-6)
    assert np.all(time_from_rest(far, v, a, j) > time_to_stop(far, v, a))
    assert time_from_rest(far, v, a, 1e9) == pytest.approx(time_to_stop(far, v, a), abs=2e-6)
    slow = 1.0  # [rad/s] below a^2 / j = 1.5: the acceleration peaks at sqrt(vmax j) and the climb takes 2 sqrt(v/j)
    assert distance_from_rest(10.0, slow, a, j) == pytest.approx(slow * (10.0 - np.sqrt(slow / j)))


@pytest.mark.slow
def test_the_bound_is_the_joint_speed_limit_and_the_expert_never_beats_it(make_env):
    """A box standing at x = 0.45 m, the red bin: each leg of the bound is the largest joint move over its
    datasheet speed, each leg of the ruckig reference is ruckig's own plan (never shorter), the bounds with
    acceleration and then jerk lie between, and the expert's measured cycle on tracking-fast, its waits for the
    boxes taken out, is no shorter than the tightest bound (jerk) of any bin."""
    from studies.cycle_bound import LEGS, commanded_peaks, cycle_at, shortest_cycle, waiting_time

    from colorsort.config import BIN_COLORS
    from colorsort.expert.planning import Waypoint, plan_motion
    from colorsort.expert.tracking import carry_height

    env = make_env(preset="tracking-fast", has_offscreen_renderer=True, seed=0)
    obs = env.reset()
    expert = make_expert(env)
    L, cfg, vmax = expert.layout, expert.config, expert.calibration.max_velocity
    top = L.belt_top_z + L.box_size
    q_over = expert.ik.solve(Waypoint("over", (0.45, L.belt_y, expert.descent.start), expert.cup_yaw), expert.q_wait)
    q_on = expert.ik.solve(Waypoint("on", (0.45, L.belt_y, top), expert.cup_yaw), q_over)
    bound, stops, jerk, reference = (cycle_at(expert, 0.45, "red", mode)
                                     for mode in ("speed", "stops", "jerk", "ruckig"))
    assert bound.legs["down onto the box"] == pytest.approx(np.max(np.abs(q_on - q_over) / vmax))
    lifted = top + cfg.track_lift_gap * 0.5  # halfway up, where the carry takes over
    assert top + carry_height(cfg) == pytest.approx(lifted)
    q_lift = expert.ik.solve(Waypoint("lifted", (0.45, L.belt_y, lifted), expert.cup_yaw), q_on)
    assert bound.legs["lift"] == pytest.approx(np.max(np.abs(q_lift - q_on) / vmax))
    assert reference.legs["down onto the box"] == pytest.approx(plan_motion(q_over, q_on, expert.limits).duration)
    assert bound.legs["seal"] == bound.legs["release"] == expert.dt
    a, v = expert.limits.acceleration, expert.limits.velocity  # per joint: up to top speed, or only part way
    d = np.abs(q_on - q_over)
    by_hand = np.where(d >= v**2 / (2 * a), d / v + v / (2 * a), np.sqrt(2 * d / a))
    assert stops.legs["down onto the box"] == pytest.approx(np.max(by_hand))
    assert all(reference.legs[leg] >= jerk.legs[leg] >= stops.legs[leg] >= bound.legs[leg] for leg in LEGS)
    assert bound.total == pytest.approx(sum(bound.legs.values()))
    fastest = min(shortest_cycle(expert, c, "jerk").total for c in BIN_COLORS)

    expert.reset(obs)
    active, waited, references, phases, boxes = 0, 0.0, [], [], 6
    while len(env.events) < boxes:
        active += expert.phase.value in ("intercept box", "track box", "lift box", "move over bin", "release")
        before = expert.phase.value
        action = expert.act(obs)
        if expert.phase.value == "intercept box" and before != "intercept box":  # less the wait for the box
            waited += waiting_time(expert.motion.trajectory, expert.limits)
        references.append(expert.motion.sample(expert.time)[0])
        phases.append(expert.phase.value)
        obs, *_ = env.step(action)
    assert (active * env.control_timestep - waited) / boxes >= fastest
    peaks = commanded_peaks(np.array(references), phases, env.control_timestep)
    for phase, (acceleration, jerk) in peaks.items():  # every phase, the dense track's too, within the limits
        assert np.all(acceleration <= expert.limits.acceleration * 1.01), phase
        assert np.all(jerk <= expert.limits.jerk * 1.01), phase


def test_commanded_peaks_are_the_reference_finite_differences_per_phase():
    """q = j t^3 / 6 sampled every 50 ms: the acceleration is j t at each middle row, the jerk j throughout; per
    joint (the second moves half as much)."""
    from studies.cycle_bound import commanded_peaks

    dt, j = 0.05, 60.0
    t = dt * np.arange(10)
    q = np.stack([j * t**3 / 6, -j * t**3 / 12], axis=1)
    peaks = commanded_peaks(q, ["a"] * 5 + ["b"] * 5, dt)
    np.testing.assert_allclose(peaks["a"], [[j * t[4], j * t[4] / 2], [j, j / 2]])  # middle rows 1..4: phase a
    np.testing.assert_allclose(peaks["b"], [[j * t[8], j * t[8] / 2], [j, j / 2]])
