"""The batched cell on MuJoCo Warp (``colorsort.batched``), on Warp's CPU device: CI has no GPU.

Warp compiles MuJoCo Warp's kernels once per machine (minutes on 2 cores: docs/gpu.md) into its disk cache
(~/.cache/warp), so only the first cell a run builds pays for it; each test then builds its own few worlds.
The rule kernels are held to their Python twins on synthetic states in ``test_twins.py``.
"""

from __future__ import annotations

import json
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import console_script, exit_status

from colorsort.batched.schedule import COLOR_NAMES, episode_draws
from colorsort.benchmark.policies import ExpertPolicy
from colorsort.cell.referee import Outcome
from colorsort.config import BIN_COLORS
from colorsort.envs.gym_env import ColorSortGymEnv
from colorsort.variants import get_variant

SEED = 10_000  # the first evaluation seed of `default`: its first box, red, is placed at 6.4 s by the expert
REPLAY_STEPS = 140  # control steps of the expert replayed: the first box is in its bin by then


@pytest.mark.parametrize("variant", ["tracking-jitter", "lighting"])
def test_a_seed_gives_the_batched_cell_the_cpu_cells_boxes(variant):
    """The host-side draws (colour, offset, yaw of every box; the lights) are those the CPU cell draws."""
    env = ColorSortGymEnv(variant, cameras=(), render_mode=None)
    try:
        for seed in (SEED, SEED + 7):
            env.reset(seed=seed)
            hold = np.r_[env.env.robot_spec.home, -1.0, -1.0].astype(np.float32)
            for _ in range(260):
                env.step(hold)
            placed = env.env.placements
            draws = episode_draws(get_variant(variant), seed, len(placed))
            assert len(placed) >= 2
            assert [p.color for p in placed] == [COLOR_NAMES[c] for c in draws.color]
            np.testing.assert_allclose([p.offset for p in placed], draws.offset, atol=1e-12)
            np.testing.assert_allclose([p.yaw for p in placed], np.rad2deg(draws.yaw), atol=1e-9)
            assert env.env.plant.lighting == draws.lighting
    finally:
        env.close()


@pytest.fixture(scope="module")
def replay():
    """The CPU cell's expert on `default`, seed SEED: its actions, observations and events."""
    env = ColorSortGymEnv("default", cameras=("sensor",), image_size=(64, 64), render_mode=None)
    expert = ExpertPolicy()
    obs, _ = env.reset(seed=SEED)
    expert.reset(env, SEED)
    actions, states = [], []
    for _ in range(REPLAY_STEPS):
        action = expert.act(obs)
        obs, *_ = env.step(action)
        actions.append(action)
        states.append(obs["agent_pos"])
    from colorsort.batched.spec import CellSpec

    spec = CellSpec.from_env(env.env)
    events = [(e.color, e.outcome.value, e.bin) for e in env.env.events]
    env.close()
    return spec, np.array(actions), np.array(states), events


@pytest.mark.slow
def test_the_batched_cell_carries_seals_and_bins_a_box_as_the_cpu_cell_does(replay):
    """Three worlds on Warp's CPU device: world 0 replays the CPU cell's expert (its box rides the belt, is sealed
    to the cup, lifted, let go and lands in the bin of its colour, as on the CPU); world 1 holds the arm (its box
    moves at belt speed); world 2 is reset mid-run to another seed while the others run on."""
    from colorsort.batched.cell import BatchedCell

    spec, actions, states, events = replay
    cell = BatchedCell(spec, get_variant("default"), 3, device="cpu", max_boxes=8)
    out = cell.reset([SEED, SEED, SEED])
    box_x = out.env_state.numpy()[:, 5]
    assert np.allclose(box_x, spec.layout.spawn_x, atol=1e-6)
    hold = np.r_[spec.qpos0[spec.arm_qpos], -1.0, -1.0]
    sealed, lifted, xs = [], [], []
    sealed_index = 2 * spec.n_joints + 7 + 1  # observation.state: joints, velocities, eef pose, then the flags
    for k, action in enumerate(actions):
        out = cell.step(np.stack([action, hold, hold]))
        state, env_state = out.state.numpy(), out.env_state.numpy()
        sealed.append(state[0, sealed_index])
        lifted.append(env_state[0, 7] if env_state[0, -1] else np.nan)
        xs.append(env_state[1, 5])
        if k == 60:
            before = cell.d.qpos.numpy()[0].copy()
            out = cell.reset([SEED + 1], worlds=[2])
            assert (cell.d.qpos.numpy()[0] == before).all()  # the other worlds do not notice
            first = COLOR_NAMES[int(np.argmax(out.env_state.numpy()[2, :5]))]
            assert first == COLOR_NAMES[episode_draws(get_variant("default"), SEED + 1, 1).color[0]]
            assert out.env_state.numpy()[2, 5] == pytest.approx(spec.layout.spawn_x, abs=1e-6)
    speed = (xs[5] - xs[15]) / (10 * cell.control_dt)
    assert speed == pytest.approx(spec.config.belt_speed, rel=0.05)  # carried by the belt's friction
    assert max(sealed) == 1.0 and sealed[-1] == 0.0  # sealed, then let go
    belt_top = spec.layout.belt_top_z + spec.layout.box_size / 2
    assert np.nanmax(lifted) > belt_top + 0.1  # the cup lifted the box
    warp_events = [(COLOR_NAMES[c], list(Outcome)[o].value, BIN_COLORS[b] if b >= 0 else None)
                   for _, _, c, o, b in cell.events(0)]
    assert warp_events[:1] == events[:1] and warp_events[0][1] == "placed"  # into the bin of its colour
    # the replay's joint states follow the CPU cell's (float32 physics, same controller): within a few mrad
    assert np.abs(out.state.numpy()[0, : spec.n_joints] - states[-1][: spec.n_joints]).max() < 0.01


@pytest.mark.slow
def test_warp_backend_evaluation_gives_the_cpu_cells_episode_outcomes_and_films(tmp_path):
    """docs/gpu.md's `colorsort-eval --backend warp --device cpu` command, as written, on the shipped state policy:
    each of its 2 episodes ends as on the CPU cell, with the same boxes, outcomes and bins; its report films both
    as the CPU cell's report does, a frame per step, each frame alike."""
    from colorsort.cli.eval import main
    from colorsort.data.video import read_video

    page = (Path(__file__).resolve().parents[1] / "docs" / "gpu.md").read_text()
    (command,) = [line for line in page.splitlines() if line.startswith("colorsort-eval") and "--device cpu" in line]
    argv = shlex.split(command)[1:]
    assert "--report" in argv
    argv[argv.index("--report") + 1] = str(tmp_path / "warp-report")
    assert main([*argv, "--json", str(tmp_path / "warp.json")]) == 0
    drop = {argv.index(flag) + k for flag in ("--backend", "--device", "--envs", "--report") for k in (0, 1)}
    cpu = [a for i, a in enumerate(argv) if i not in drop]  # the CPU cell in this process (seeds alone set episodes)
    assert main([*cpu, "--json", str(tmp_path / "cpu.json"), "--report", str(tmp_path / "cpu-report")]) == 0
    warp, cpu = (json.loads((tmp_path / f"{b}.json").read_text()) for b in ("warp", "cpu"))

    def outcome(report):
        return [(e["seed"], e["ended"], [(b["color"], b["outcome"], b["bin"]) for b in e["boxes"]])
                for e in report["per_episode"]]

    assert outcome(warp) == outcome(cpu)
    assert sum(len(e["boxes"]) for e in warp["per_episode"]) >= 1  # a box was sorted in the horizon
    names = sorted(p.name for p in (tmp_path / "warp-report" / "videos").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "cpu-report" / "videos").iterdir()) and len(names) == 2
    for name, episode in zip(names, warp["per_episode"], strict=True):
        films = [read_video(tmp_path / f"{b}-report" / "videos" / name) for b in ("warp", "cpu")]
        assert len(films[0]) == len(films[1]) == episode["steps"] + 1  # the reset, then every step
        warp_frames, cpu_frames = (f.astype(np.float32) for f in films)
        # the same renderer on states within mrad of each other: every frame within a few grey levels in 255 (both
        # H.264; measured: at most 2.2 and 0.8, 0.0 to 0.1 at the reset)
        assert np.abs(warp_frames - cpu_frames).mean(axis=(1, 2, 3)).max() < 4.0


def test_the_default_install_path_never_imports_warp():
    code = ("import sys, colorsort, colorsort.cli.eval, colorsort.benchmark.evaluate, colorsort.cli.baseline; "
            "sys.exit('warp' in sys.modules or 'mujoco_warp' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0


@pytest.mark.parametrize("args, message", [
    (["--device", "cpu"], "--device: only --backend warp"),
    (["--backend", "warp", "--executor", "ray"], "--backend warp runs on one device, not on an --executor"),
])
def test_warp_backend_arguments_are_checked(args, message, capsys):
    from colorsort.cli.eval import main

    assert exit_status(main, ["--policy", "expert", *args]) == 2
    assert message in capsys.readouterr().err


def test_the_expert_is_refused_on_the_warp_backend_by_name():
    from colorsort.benchmark.lockstep import BatchedPolicy

    with pytest.raises(ValueError, match="the expert reads the sensor camera"):
        BatchedPolicy("expert", "cpu", np.zeros(8), np.ones(8))


@pytest.mark.slow
def test_gymnasium_make_vec_steps_the_batched_cell_and_resets_finished_envs_in_the_same_step():
    """`gym.make_vec(..., vectorization_mode="vector_entry_point")`: the CPU env's spaces, boxes riding the belt,
    and an episode that ends (here at its step limit) starts again in the same step with the env's next seed."""
    import gymnasium as gym

    envs = gym.make_vec("colorsort/ColorSort-v0", num_envs=2, vectorization_mode="vector_entry_point",
                        device="cpu", episode_length=3)
    try:
        obs, info = envs.reset(seed=SEED)
        assert envs.observation_space.contains(obs)
        assert envs.call("_max_episode_steps") == (3, 3)
        spec = envs.unwrapped.cell.spec
        hold = np.tile(np.r_[spec.qpos0[spec.arm_qpos], -1.0, -1.0], (2, 1)).astype(np.float32)
        for _ in range(2):
            obs, reward, terminated, truncated, info = envs.step(hold)
            assert not (terminated | truncated).any()
        assert (obs["environment_state"][:, 5] < spec.layout.spawn_x - 0.005).all()  # the boxes ride the belt
        obs, reward, terminated, truncated, info = envs.step(hold)
        assert truncated.all() and not terminated.any()
        assert (info["final_obs"]["environment_state"][:, 5] < spec.layout.spawn_x - 0.005).all()
        np.testing.assert_allclose(obs["environment_state"][:, 5], spec.layout.spawn_x, atol=1e-6)  # a new episode
        first = [COLOR_NAMES[episode_draws(get_variant("default"), s, 1).color[0]] for s in (SEED + 2, SEED + 3)]
        assert [COLOR_NAMES[int(np.argmax(e[:5]))] for e in obs["environment_state"]] == first
    finally:
        envs.close()


@pytest.mark.slow
def test_lerobot_eval_runs_on_the_batched_cell_as_documented(tmp_path):
    """docs/gpu.md's lerobot-eval command, as written (from a folder holding the shipped baselines; by its entry
    point in this process): LeRobot's evaluator steps its envs as one batched cell, scores the episodes and films
    them."""
    page = (Path(__file__).resolve().parents[1] / "docs" / "gpu.md").read_text().replace("\\\n", " ")
    (line,) = [line for line in page.splitlines() if "lerobot-eval" in line and "--env.backend=warp" in line]
    argv = shlex.split(line)
    assert argv[0] == "HF_HUB_OFFLINE=1"
    (tmp_path / "baselines").symlink_to(Path(__file__).resolve().parents[1] / "baselines")
    done = console_script(argv[1], argv[2:], tmp_path)
    assert done.returncode == 0, (done.stdout + done.stderr)[-3000:]
    (info,) = (tmp_path / "outputs" / "eval").rglob("eval_info.json")
    overall = json.loads(info.read_text())["overall"]
    assert overall["n_episodes"] == 2
    assert all((tmp_path / p).stat().st_size > 1000 for p in overall["video_paths"])


@pytest.mark.slow
@pytest.mark.parametrize("variant", ["tracking-fast", "robots-panda"])
def test_other_belts_and_robots_run_on_the_batched_cell(variant):
    """A tracking belt (its encoder in observation.state) and a 7-joint arm: the boxes ride the belt at the
    variant's speed, the observation has the CPU env's size, and the held arm stays at home."""
    from colorsort.batched.cell import BatchedCell
    from colorsort.batched.spec import spec_for_variant

    v = get_variant(variant)
    spec = spec_for_variant(variant)
    cell = BatchedCell(spec, v, 2, device="cpu", max_boxes=8)
    out = cell.reset([SEED, SEED + 1])
    single = ColorSortGymEnv(variant, cameras=(), render_mode=None)
    assert out.state.shape == (2, single.observation_space["agent_pos"].shape[0])
    hold = np.tile(np.r_[spec.qpos0[spec.arm_qpos], -1.0, -1.0], (2, 1))
    xs = []
    for _ in range(12):
        out = cell.step(hold)
        xs.append(out.env_state.numpy()[:, 5].copy())  # the cell's buffer: the next step overwrites it
    speed = (xs[2] - xs[-1]) / (9 * cell.control_dt)
    np.testing.assert_allclose(speed, v.task_config.belt_speed, rtol=0.05)
    np.testing.assert_allclose(out.state.numpy()[:, : spec.n_joints], np.tile(spec.qpos0[spec.arm_qpos], (2, 1)),
                               atol=0.01)
    if v.task_config.tracking:  # the encoder: the belt never stopped
        np.testing.assert_allclose(out.state.numpy()[:, -1], 12 * cell.control_dt * v.task_config.belt_speed,
                                   rtol=1e-4)


@pytest.mark.parametrize("limit", [None, 1, 2, 5])
def test_the_episodes_kept_wave_by_wave_hold_every_film_the_report_chooses(limit):
    """``films.wanted`` keeps, wave by wave, what ``choose_films`` would choose from every episode at the end."""
    from colorsort.batched.films import wanted
    from colorsort.benchmark.episode_result import EpisodeResult
    from colorsort.benchmark.metrics import aggregate
    from colorsort.benchmark.report_page import choose_films

    rng = np.random.default_rng(0)
    for _ in range(20):
        episodes = [EpisodeResult(seed=100 + i, success=bool(rng.random() < 0.6), ended="x", steps=1, correct=0,
                                  misplaced=0, dropped=0, let_through=0, distractors=0, sim_time=1.0,
                                  sorted_times=[], boxes=[]) for i in range(int(rng.integers(1, 15)))]
        kept, have = set(), (0, 0)
        for first in range(0, len(episodes), 4):  # waves of 4 worlds
            wave = episodes[first : first + 4]
            chosen, have = wanted(wave, limit, have)
            kept |= {wave[i].seed for i in chosen}
        report = aggregate("p", "default", episodes)
        everything = choose_films([report], {("default", e.seed): e.seed for e in episodes}, limit)
        assert set(everything.values()) <= kept


@pytest.mark.slow
def test_a_world_that_finished_starts_the_next_seed_and_every_seed_plays_as_on_its_own():
    """Rolling evaluation: 3 seeds on 2 worlds (the third starts in the first world free at a refill of ACT's queue
    of actions) give every seed the episode one wave of 3 worlds gives it: the same boxes into the same bins, ended
    the same way after as many steps. The times a box settled may differ by a few control steps: the policy's
    batch of 2 or 3 rounds its last bits differently, and the contacts carry that on (measured: 0.05-0.1 s, in
    seed 10000's world 0 too, which runs from the first step in both)."""
    from colorsort.batched.evaluate import evaluate_batched
    from colorsort.batched.spec import spec_for_variant

    spec = spec_for_variant("default")

    def episodes(envs: int) -> list:
        run = evaluate_batched("baselines/act-state", "default", 3, envs=envs, device="cpu", episode_length=160,
                               progress=False, spec=spec)
        return run.report.per_episode, run.timing

    (rolling, timing), (wave, _) = episodes(2), episodes(3)
    assert timing.worlds == 2 and timing.control_steps > 160  # the third seed ran after one of the first two
    assert [e["seed"] for e in rolling] == [SEED, SEED + 1, SEED + 2]
    assert sum(len(e["boxes"]) for e in rolling) >= 3  # boxes were sorted within the horizon

    def outcome(e: dict) -> tuple:
        return e["seed"], e["ended"], e["steps"], [(b["color"], b["outcome"], b["bin"]) for b in e["boxes"]]

    assert [outcome(e) for e in rolling] == [outcome(e) for e in wave]
    times = [(a["time"], b["time"]) for r, w in zip(rolling, wave, strict=True)
             for a, b in zip(r["boxes"], w["boxes"], strict=True)]
    assert max(abs(a - b) for a, b in times) <= 0.25  # five control steps


def test_only_a_policy_that_keeps_nothing_but_its_queue_of_actions_is_rolled():
    """``restart_period``: ACT's queue length without temporal ensembling, Diffusion Policy's on one observation;
    None (whole waves) for an ensemble of chunks or a queue of observations."""
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig

    from colorsort.benchmark.lockstep import restart_period

    assert restart_period(ACTConfig(chunk_size=20, n_action_steps=10)) == 10
    assert restart_period(ACTConfig(chunk_size=20, n_action_steps=1, temporal_ensemble_coeff=0.01)) is None
    assert restart_period(DiffusionConfig(n_obs_steps=1, horizon=16, n_action_steps=8)) == 8
    assert restart_period(DiffusionConfig(n_obs_steps=2, horizon=16, n_action_steps=8)) is None


def test_a_cuda_device_without_a_gpu_exits_2_with_one_line_that_names_the_cpu_device(capsys):
    """``--backend warp --device cuda:0`` where no GPU is visible: exit 2 and ColorSort's line (not torch's driver
    message, exit 1); a device that is neither cpu nor cuda:N names both."""
    import warp as wp

    from colorsort.cli.eval import main

    if wp.get_cuda_device_count():
        pytest.skip("a GPU is visible here")
    assert exit_status(main, ["--backend", "warp", "--device", "cuda:0", "--episodes", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "no CUDA device is visible" in err and "--device cpu runs Warp's CPU device" in err
    assert exit_status(main, ["--backend", "warp", "--device", "gpu", "--episodes", "1"]) == 2
    assert "give cpu (Warp's CPU device) or cuda:N" in capsys.readouterr().err
