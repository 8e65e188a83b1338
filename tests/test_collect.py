"""The collector: refuses to overwrite, resumes after an interruption, and is worker-count independent."""

import json
import shutil
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from helpers import TINY, exit_status

from colorsort.cli.args import parse_image_size
from colorsort.cli.collect import main
from colorsort.data import recorder as recorder_module
from colorsort.data.collect import collect
from colorsort.data.config import CollectConfig
from colorsort.data.perturbations import PERTURBATIONS, Step, parse, perturbed
from colorsort.data.perturbations.brightness import Brightness
from colorsort.data.perturbations.late_pass import LatePass
from colorsort.data.perturbations.late_pick import LatePick
from colorsort.data.store import MARKER
from colorsort.executors.base import ExecutorConfig, chunks
from colorsort.expert.sorter import SortingExpert

REPO = Path(__file__).resolve().parents[1]


def data_table(root):
    """Every frame's columns, in dataset order (one parquet file at this size)."""
    (path,) = sorted((root / "data").rglob("*.parquet"))
    return pq.read_table(path).to_pydict()


def snapshot(root):
    return {p.relative_to(root): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("kwargs, match", [
    (dict(cameras=("top",)), "scene"), (dict(fps=30), "Valid values"), (dict(vcodec="mjpeg"), "h264"),
    (dict(preset="nope"), "Valid presets"), (dict(robot="KUKA"), "Valid robots"),
    (dict(image_size=(63, 64)), "even"),
    (dict(resume=True, overwrite=True), "not both"),
    (dict(perturbations=(Brightness(0.5, 0.9),)), "lighting"),
    (dict(variant="jitter", perturbations=(Brightness(0.5, 0.9),)), "lighting"),
    (dict(variant="lighting", perturbations=(Brightness(0.5, 0.9), Brightness(0.6, 0.9))), "twice"),
    (dict(preset="tracking", perturbations=(LatePick(5),)), "tracking belt"),
])
def test_bad_settings_name_the_valid_choices(kwargs, match):
    with pytest.raises(ValueError, match=match):
        CollectConfig(**kwargs)
    with pytest.raises(ValueError, match="valid values"):  # the executor group checks its own fields
        ExecutorConfig(workers=0)


@pytest.mark.parametrize("make, match", [
    (lambda: Brightness(0.9, 0.5), "brightness"), (lambda: Brightness(0.01, 0.5), "brightness"),
    (lambda: LatePick(101), "late_pick"), (lambda: LatePick(-1), "late_pick"), (lambda: LatePass(-1), "late_pass"),
    (lambda: parse("late_pass", "many"), "late_pass"), (lambda: parse("brightness", "dim"), "low,high"),
    (lambda: parse("early_pick", "3"), "Valid perturbations"),
])
def test_a_perturbation_checks_its_own_settings_once(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_perturbations_are_one_registry_with_one_protocol():
    """Each registered perturbation parses what it prints, tags and describes itself, and records its settings;
    an inactive one (0 steps) is dropped from a configuration, and they keep the order of their names."""
    assert set(PERTURBATIONS) == {"brightness", "late_pass", "late_pick"}
    for example in ("0.45,0.75", "100", "10"):
        for name, kind in PERTURBATIONS.items():
            try:
                p = kind.parse(example)
            except ValueError:
                continue
            assert p.name == name and kind.parse(p.text) == p and p.tag and p.describe()
            json.dumps(p.settings())
    config = CollectConfig(variant="lighting", perturbations=(LatePick(5), LatePass(0), Brightness(0.45, 0.75)))
    assert [p.name for p in config.perturbations] == ["brightness", "late_pick"]
    assert config.settings()["brightness"] == [0.45, 0.75] and config.settings()["late_pick"] == 5
    assert "late_pass" not in config.settings() and "late_pick" not in CollectConfig().settings()


def test_image_size_and_split():
    assert parse_image_size("96") == (96, 96) and parse_image_size("96x128") == (96, 128)
    with pytest.raises(ValueError):
        parse_image_size("big")
    assert chunks(list(range(5)), 32, 2) == [[0, 1], [2, 3, 4]] and chunks([7], 32, 3) == [[7]]
    assert chunks(list(range(5)), 2, 1) == [[0], [1, 2], [3, 4]] and chunks([], 4, 2) == []


def test_an_existing_dataset_is_never_overwritten_silently(tiny_dataset, tmp_path, capsys):
    copy = tmp_path / "copy"
    shutil.copytree(tiny_dataset, copy)
    before = snapshot(copy)
    with pytest.raises(FileExistsError, match="--resume"):
        collect(CollectConfig(out=str(copy), **TINY), progress=False)
    assert main(["--out", str(copy), "--episodes", "2", "--image-size", "64"]) == 2
    assert "already exists" in capsys.readouterr().err
    assert snapshot(copy) == before


def test_overwrite_refuses_a_folder_that_is_not_a_dataset(tmp_path):
    (tmp_path / "notes.txt").write_text("keep me")
    with pytest.raises(FileExistsError, match="not a LeRobot dataset"):
        collect(CollectConfig(out=str(tmp_path), overwrite=True, **TINY), progress=False)
    assert (tmp_path / "notes.txt").read_text() == "keep me"


def test_resume_with_other_settings_is_refused(tiny_dataset, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(tiny_dataset, copy)
    with pytest.raises(ValueError, match="other settings"):
        collect(CollectConfig(out=str(copy), resume=True, **{**TINY, "image_size": (96, 96)}), progress=False)


def test_resume_without_the_turn_is_refused_and_older_datasets_resume_as_before(tiny_dataset, tmp_path):
    """``turn_to_box`` is a setting of the data: recorded when off, absent (as in older datasets) when on."""
    assert "turn_to_box" not in CollectConfig(**TINY).settings()
    assert CollectConfig(**TINY, turn_to_box=False).settings()["turn_to_box"] is False
    copy = tmp_path / "copy"
    shutil.copytree(tiny_dataset, copy)
    with pytest.raises(ValueError, match="turn_to_box"):
        collect(CollectConfig(out=str(copy), resume=True, **{**TINY, "turn_to_box": False}), progress=False)


def test_the_experts_changed_settings_are_a_setting_of_the_data(tiny_dataset, tmp_path, capsys):
    """``--expert`` changes the recording expert's settings, is recorded (absent when unset, as in older datasets)
    and checked on resume; a name it cannot change or a value out of range is refused naming the valid ones."""
    deeper = CollectConfig(**TINY, preset="tracking", expert=(("press", 0.01), ("track_hold_time", 0.15)))
    assert (deeper.expert_config.press, deeper.expert_config.track_hold_time) == (0.01, 0.15)
    assert deeper.expert_config.touch_speed == CollectConfig(**TINY, preset="tracking").expert_config \
        .touch_speed  # the rest is the tracking belt's preset
    assert deeper.settings()["expert"] == [["press", 0.01], ["track_hold_time", 0.15]]
    assert "expert" not in CollectConfig(**TINY).settings()
    copy = tmp_path / "copy"
    shutil.copytree(tiny_dataset, copy)
    with pytest.raises(ValueError, match="expert"):
        collect(CollectConfig(out=str(copy), resume=True, **TINY, expert=(("press", 0.01),)), progress=False)
    with pytest.raises(ValueError, match="valid names: .*'track_hold_time'"):
        CollectConfig(**TINY, expert=(("hold", 0.15),))
    assert exit_status(main, ["--expert", "press:0.5", "--out", str(tmp_path / "new")]) == 2
    assert "press=0.5 is out of range" in capsys.readouterr().err
    assert not (tmp_path / "new").exists()


@pytest.mark.slow
def test_interrupted_run_keeps_finished_episodes_and_resume_completes_it(tiny_dataset, tmp_path, monkeypatch):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    out = tmp_path / "ds"
    steps = {"n": 0}
    act = SortingExpert.act

    def act_then_ctrl_c(self, obs):  # Ctrl-C in the middle of the second episode
        steps["n"] += 1
        if steps["n"] == 200:
            raise KeyboardInterrupt
        return act(self, obs)

    monkeypatch.setattr(SortingExpert, "act", act_then_ctrl_c)
    summary = collect(CollectConfig(out=str(out), **TINY), progress=False, log=lambda _: None)
    assert summary.interrupted and summary.kept == 1
    assert LeRobotDataset("local/colorsort", root=out, video_backend="pyav").num_episodes == 1  # loadable
    assert json.loads((out / MARKER).read_text())["tried"] == [0]
    assert not (tmp_path / ".ds.staging").exists()

    monkeypatch.setattr(SortingExpert, "act", act)
    summary = collect(CollectConfig(out=str(out), resume=True, **TINY), progress=False, log=lambda _: None)
    assert summary.kept == 1 and summary.tried == 1 and not summary.interrupted
    resumed = LeRobotDataset("local/colorsort", root=out, video_backend="pyav")
    assert resumed.num_episodes == 2
    assert data_table(out)["sim_state"] == data_table(tiny_dataset)["sim_state"]  # same as one straight run
    assert resumed[len(resumed) - 1]["observation.images.scene"].shape == (3, 64, 64)  # videos joined too


@pytest.mark.slow
def test_ctrl_c_while_an_episode_is_saved_drops_the_shard_and_resume_records_it_again(tiny_dataset, tmp_path,
                                                                                      monkeypatch):
    """LeRobot's save_episode takes the frame count out of its buffer first: an interrupt (a Ray cancel) after that
    leaves a half-written shard, which is dropped (no marker) instead of crashing; --resume records it again."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    out = tmp_path / "ds"
    save = LeRobotDataset.save_episode
    calls = {"n": 0}

    def save_cut_short(self, *args, **kwargs):  # the second episode's save is interrupted half-way
        calls["n"] += 1
        if calls["n"] == 2:
            self.writer.episode_buffer.pop("size")
            raise KeyboardInterrupt
        return save(self, *args, **kwargs)

    monkeypatch.setattr(LeRobotDataset, "save_episode", save_cut_short)
    summary = collect(CollectConfig(out=str(out), **TINY), progress=False, log=lambda _: None)
    assert summary.interrupted and not summary.errors
    assert not (out / MARKER).exists()  # nothing trustworthy was published

    monkeypatch.setattr(LeRobotDataset, "save_episode", save)
    summary = collect(CollectConfig(out=str(out), resume=True, **TINY), progress=False, log=lambda _: None)
    assert summary.kept == 2 and not summary.interrupted
    assert data_table(out)["sim_state"] == data_table(tiny_dataset)["sim_state"]  # same as one straight run


@pytest.mark.slow
def test_same_seeds_give_the_same_data_whatever_the_worker_count_or_cameras(tiny_dataset, tmp_path):
    """The tiny dataset's episodes (one process, two cameras) recorded again by two worker processes without
    cameras: every frame's state, action and simulator state the same (the images are in its videos)."""
    out = tmp_path / "two_workers"
    config = CollectConfig(out=str(out), executor=ExecutorConfig(workers=2), **{**TINY, "cameras": ()})
    summary = collect(config, progress=False, log=lambda _: None)
    assert summary.kept == 2 and not summary.errors
    one, two = data_table(tiny_dataset), data_table(out)
    assert one.keys() == two.keys()
    for key in one:
        assert np.array_equal(np.asarray(one[key]), np.asarray(two[key])), key
    assert json.loads((out / MARKER).read_text())["episodes"] == [0, 1]


def test_failed_episodes_are_tried_counted_and_not_kept(tmp_path, monkeypatch):
    monkeypatch.setattr(recorder_module, "episode_time_limit", lambda config: 1.0)  # no box gets sorted in 1 s
    summary = collect(CollectConfig(out=str(tmp_path / "ds"), **TINY), progress=False, log=lambda _: None)
    assert summary.tried == 2 and summary.kept == 0 and summary.not_kept == {"timeout": 2}
    assert not (tmp_path / "ds").exists()


@pytest.mark.slow
def test_cli_records_several_boxes_per_episode_and_prints_the_summary(tmp_path, capsys):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    out = tmp_path / "two_boxes"
    assert main(["--episodes", "1", "--boxes-per-episode", "2", "--cameras", "sensor", "--image-size", "32",
                 "--out", str(out), "--repo-id", "test/two-boxes"]) == 0
    printed = capsys.readouterr().out
    assert "tried 1, kept 1" in printed and "MB on disk" in printed and "LeRobotDataset('test/two-boxes'" in printed
    ds = LeRobotDataset("test/two-boxes", root=out, video_backend="pyav")
    assert ds.meta.episodes[0]["tasks"] == ["Sort the next 2 boxes from the conveyor into the bins of their colours."]
    assert ds.num_frames > 200  # two boxes: the second rides in behind the first
    assert tuple(ds[0]["observation.images.sensor"].shape) == (3, 32, 32)


def test_a_state_only_dataset_loads_in_lerobot_with_no_video_features(tmp_path):
    """--cameras none: no video features (the expert still takes its own sensor photo). (lerobot-train on such a
    dataset: test_lerobot_cli's diffusion commands and test_pipeline's state recipe.)"""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    root = tmp_path / "state_only"
    assert main(["--episodes", "1", "--boxes-per-episode", "1", "--cameras", "none", "--out", str(root)]) == 0
    dataset = LeRobotDataset("local/colorsort", root=root)
    assert dataset.meta.video_keys == [] and dataset.num_episodes == 1 and not list(root.rglob("*.mp4"))
    item = dataset[len(dataset) - 1]
    assert {"observation.state", "observation.environment_state", "action"} <= set(item)
    assert not any(k.startswith("observation.images") for k in item)


@pytest.mark.slow
def test_a_variant_records_the_benchmarks_own_episode_for_each_seed(tmp_path):
    """--variant jitter: the recorded episode is the one the benchmark's env gives for that seed (box off the
    centre line and turned), replay rebuilds the variant's task, and the marker says which variant."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    from colorsort.data.replay import replay
    from colorsort.envs.gym_env import ColorSortGymEnv
    from colorsort.variants import get_variant

    root = tmp_path / "jitter"
    assert main(["--variant", "jitter", "--episodes", "1", "--seed", "7", "--cameras", "none", "--out", str(root)]) == 0
    assert json.loads((root / MARKER).read_text())["settings"]["variant"] == "jitter"
    first = LeRobotDataset("local/colorsort", root=root)[0]["observation.environment_state"].numpy()
    env = ColorSortGymEnv(get_variant("jitter"), cameras=())
    obs, _ = env.reset(seed=7)
    env.close()
    np.testing.assert_array_equal(first, obs["environment_state"])
    default_env = ColorSortGymEnv(get_variant("default"), cameras=())
    default_obs, _ = default_env.reset(seed=7)
    default_env.close()
    assert not np.array_equal(first[5:12], default_obs["environment_state"][5:12])  # jitter moved or turned the box
    report = replay(root, 0, camera="scene", size=(32, 32), video=None, sheet=None, progress=False)
    assert report.state_replay_ok and report.action_replay_ok and report.outcomes == ["placed"]


def test_a_variant_and_a_preset_or_robot_are_not_given_together(capsys):
    assert exit_status(main, ["--variant", "jitter", "--robot", "Panda"]) == 2
    assert "--variant" in capsys.readouterr().err
    with pytest.raises(ValueError, match="give the variant alone"):
        CollectConfig(variant="robots-panda")  # robot IRB140 by default, the variant's is Panda
    with pytest.raises(ValueError, match="Valid variants"):
        CollectConfig(variant="nope")


@pytest.mark.slow
def test_late_pass_holds_the_belt_back_and_stores_the_experts_action(tmp_path):
    """Seed 2 of distractors starts with a purple box: the expert lets it through at once; with
    --late-pass the belt stays stopped for the drawn steps while the stored action says belt-pass."""
    from colorsort.data.perturbations import late_pass

    def late_frames(steps):
        out = tmp_path / f"late{steps}"
        summary = collect(CollectConfig(variant="distractors", episodes=1, seed=2, cameras=(),
                                        perturbations=(LatePass(steps),), out=str(out)),
                          progress=False, log=lambda _: None)
        assert summary.kept == 1  # the purple box left the belt; nothing was misplaced or dropped
        table = data_table(out)
        state, action = np.array(table["observation.state"]), np.array(table["action"])
        ray, running = state[:, -2] > 0.5, state[:, -1] > 0.5
        return int(np.sum((action[:, -1] > 0) & ray & ~running)), int(np.sum(action[:, -1] > 0))

    delay = int(np.random.default_rng([2, late_pass.LATE_PASS_STREAM]).integers(0, 10))  # the hook's first draw, seed 2
    assert delay > 0
    (plain_late, plain_on), (late, on) = late_frames(0), late_frames(9)
    assert plain_late == 1  # the expert's own let-through: one frame of "box at the ray, belt stopped"
    assert late == 1 + delay  # then `delay` more, each labelled belt-pass
    assert plain_on + delay <= on <= plain_on + delay + 1  # the box clears the ray a step later at most


@pytest.mark.slow
def test_late_pick_holds_the_arm_at_a_picks_start_and_stores_the_experts_approach(tmp_path):
    """Seed 0 of default starts with a box of a bin colour: with --late-pick the arm stays where it waited for the
    drawn steps while every stored action is the expert's first approach action, then the expert goes on with
    its plan unchanged and the box is placed; without, one such frame. The same box either way."""
    from colorsort.data.perturbations import late_pick

    def waiting_frames(steps):
        out = tmp_path / f"pick{steps}"
        summary = collect(CollectConfig(variant="default", episodes=1, boxes_per_episode=1, seed=0, cameras=(),
                                        perturbations=(LatePick(steps),), out=str(out)),
                          progress=False, log=lambda _: None)
        assert summary.kept == 1  # the box went to its bin
        table = data_table(out)
        state, action = np.array(table["observation.state"]), np.array(table["action"])
        ray, running, suction = state[:, -2] > 0.5, state[:, -1] > 0.5, state[:, -4] > 0.5
        still = np.abs(state[:, 6:12]).max(axis=1) < 1e-3
        at_ray = np.flatnonzero(ray & ~running & ~suction & still)
        return state, action, at_ray, np.array(table["observation.environment_state"])[0]

    delay = int(np.random.default_rng([0, late_pick.LATE_PICK_STREAM]).integers(0, 10))  # the hook's first draw, seed 0
    assert delay > 0
    (state0, action0, plain, box0), (state, action, held, box) = waiting_frames(0), waiting_frames(9)
    np.testing.assert_array_equal(box, box0)  # the same box, where the plain run had it
    assert len(plain) == 1  # the expert starts its approach in the step the ray sees the box
    assert len(held) == 1 + delay and np.all(np.diff(held) == 1)
    np.testing.assert_array_equal(action[held], np.repeat(action0[plain], len(held), axis=0))  # its approach
    went = np.abs(state0[plain[0] + delay, :6] - state0[plain[0], :6]).max()  # the expert's arm, as many steps on
    assert np.abs(state[held[-1], :6] - state[held[0], :6]).max() < min(1e-3, went / 10)  # this one did not go
    after = held[-1] + 1  # from here on the expert's plan, as if it had started now
    np.testing.assert_allclose(action[after:after + 20], action0[plain[0] + 1:plain[0] + 21], atol=1e-4)


def test_a_late_pick_holds_only_an_expert_that_starts_approaching(capsys):
    """The late-pick hook holds the step in which ``Expert.approaching`` turns on, and no other: an expert with
    no approach phase (the tracking one) is never held. On the command line, a tracking belt is refused."""
    class Fixed:  # an expert whose approach turns on in its third step
        def __init__(self, approach_at: int | None):
            self.approach_at, self.steps, self.approaching = approach_at, 0, False

        def act(self, obs):
            self.steps += 1
            self.approaching = self.approach_at is not None and self.steps >= self.approach_at
            return np.array([float(self.steps), 1.0, -1.0], np.float32)

    def run(expert, steps=8):
        hook = LatePick(9).episode(0, expert)
        out = [perturbed([hook], lambda: Step(*[expert.act({})] * 2)) for _ in range(steps)]
        return [float(s.stored[0]) for s in out], [float(s.executed[0]) for s in out]

    from colorsort.data.perturbations import late_pick

    delay = int(np.random.default_rng([0, late_pick.LATE_PICK_STREAM]).integers(0, 10))
    stored, executed = run(Fixed(3), steps=4 + delay)
    assert stored[:2] == executed[:2] == [1.0, 2.0]  # before the approach: the expert's own
    assert stored[2:3 + delay] == [3.0] * (1 + delay)  # the approach's first action, stored on every held frame
    assert executed[2:2 + delay] == [2.0] * delay and executed[2 + delay] == 3.0  # the arm held, then it goes
    assert stored[3 + delay] == executed[3 + delay] == 4.0  # the expert's clock stood still meanwhile
    assert run(Fixed(None)) == ([float(k) for k in range(1, 9)],) * 2  # never approaching: never held
    assert exit_status(main, ["--variant", "tracking", "--late-pick", "5", "--episodes", "1"]) == 2
    assert "late_pick" in capsys.readouterr().err


def test_a_late_pass_holds_the_belt_pass_and_is_off_at_zero():
    action = np.array([0.1, -1.0, 1.0], np.float32)
    hook = LatePass(9).episode(2, expert=None)
    from colorsort.data.perturbations import late_pass

    delay = int(np.random.default_rng([2, late_pass.LATE_PASS_STREAM]).integers(0, 10))
    steps = [perturbed([hook], lambda: Step(action, action)) for _ in range(delay + 1)]
    assert all(s.stored is action for s in steps)
    assert [float(s.executed[-1]) for s in steps] == [-1.0] * delay + [1.0]
    assert not LatePass(0).active and CollectConfig(perturbations=(LatePass(0),)).perturbations == ()


@pytest.mark.slow
def test_brightness_records_a_lighting_demo_under_the_lights_asked_for(tmp_path):
    """--brightness LO,HI: the same episode (seed, boxes, light colour) under lights drawn from LO-HI, seen
    so by the camera, and recorded in the dataset's settings; the variant's own range otherwise."""
    def first_frame(brightness, name):
        out = tmp_path / name
        argv = ["--variant", "lighting", "--episodes", "1", "--boxes-per-episode", "1", "--seed", "3",
                "--cameras", "sensor", "--image-size", "32", "--out", str(out)]
        assert main(argv + ([f"--brightness={brightness}"] if brightness else [])) == 0
        settings = json.loads((out / "meta" / "colorsort.json").read_text())["settings"]
        from lerobot.datasets.lerobot_dataset import LeRobotDataset

        frame = LeRobotDataset("local/colorsort", root=out)[0]
        return settings, frame["observation.images.sensor"].numpy().mean(), frame["observation.state"].numpy()

    (dim_settings, dim, dim_state), (bright_settings, bright, bright_state) = (
        first_frame("0.45,0.5", "dim"), first_frame("1.5,1.6", "bright"))
    assert dim_settings["brightness"] == [0.45, 0.5] and bright_settings["brightness"] == [1.5, 1.6]
    assert dim < 0.6 * bright  # a third of the light, rendered
    assert np.array_equal(dim_state, bright_state)  # the lights alone differ
    plain, _, _ = first_frame(None, "plain")
    assert "brightness" not in plain  # recorded only where given
    assert exit_status(main, ["--variant", "lighting", "--brightness", "dim", "--out", str(tmp_path / "bad")]) == 2
    assert not (tmp_path / "bad").exists()
