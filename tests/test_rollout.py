"""The one episode loop (``envs/rollout.py``): what it asks of the actor, what each observer is told and when, how
it stops; and the loops built on it (recording, evaluation, sorting) giving the episodes they gave before it."""

import json
from pathlib import Path

import numpy as np
import pytest
from helpers import new_env

from colorsort.benchmark.evaluate import run_evaluation
from colorsort.envs.rollout import CellEpisode, Observer, Step, Stopped, rollout

GOLDEN = Path(__file__).parent / "data" / "rollout_golden.json"  # made by the four loops before they were one


class Log(Observer):
    def __init__(self):
        self.calls = []

    def on_start(self, obs):
        self.calls.append("start")

    def on_observe(self, obs):
        self.calls.append("observe")

    def on_action(self, obs, step):
        self.calls.append(("action", float(step.stored[0]), float(step.executed[0])))

    def on_step(self, obs, info):
        self.calls.append("step")


def home(env):
    low, high = env.action_spec
    return np.clip(np.concatenate([env.robot_spec.home, [-1.0, 1.0]]), low, high)


def test_observers_hear_every_step_in_order_and_the_env_takes_the_executed_action():
    env = new_env()
    try:
        obs = env.reset(seed=0)
        action = home(env)
        held = action.copy()
        held[0] += 0.3  # executed differs from stored: the first joint's target turned
        log = Log()
        ending = rollout(CellEpisode(env, boxes=1, limit=60.0), obs, lambda o: Step(action, held), [log],
                         max_steps=3)
        assert ending.steps == 3 and not ending.ended and env.timestep == 3
        assert log.calls == ["start", *(["observe", ("action", action[0], held[0]), "step"] * 3)]
        first_joint = env.mj_data.qpos[env.robots[0]._ref_joint_pos_indexes[0]]
        assert first_joint > action[0] + 1e-3  # the arm went for the executed target, not the stored one
    finally:
        env.close()


def test_an_episode_ends_on_its_own_rule_and_a_stop_raises_before_the_next_step():
    env = new_env()
    try:
        obs = env.reset(seed=0)
        ending = rollout(CellEpisode(env, boxes=1, limit=0.5), obs, lambda o: home(env))
        assert ending.ended and env.cur_time == pytest.approx(0.5, abs=env.control_timestep)
        obs = env.reset(seed=0)
        asked = []
        with pytest.raises(Stopped):
            rollout(CellEpisode(env, boxes=1, limit=60.0), obs, lambda o: home(env),
                    stop=lambda: asked.append(1) or len(asked) > 2)
        assert env.timestep == 2
    finally:
        env.close()


def rounded(x, digits=6):
    if isinstance(x, float):
        return round(x, digits)
    if isinstance(x, dict):
        return {k: rounded(v, digits) for k, v in x.items()}
    if isinstance(x, list):
        return [rounded(v, digits) for v in x]
    return x


@pytest.mark.slow
def test_evaluation_gives_the_episodes_it_gave_before_the_loops_were_one():
    report = run_evaluation("expert", ["default"], 2, cameras=("sensor",), progress=False).reports[0]
    golden = json.loads(GOLDEN.read_text())["evaluation"]
    assert rounded(report.per_episode) == rounded(golden)


def frames_summary(root: Path) -> dict:
    """Per episode: its frame count, first and last three frames and column means of the action and the state."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    data = LeRobotDataset("local/colorsort", root=root).hf_dataset.with_format("numpy")
    index = np.asarray(data["episode_index"])
    out = {}
    for e in sorted(set(index.tolist())):
        rows = np.flatnonzero(index == e)
        entry = {"frames": len(rows)}
        for key in ("action", "observation.state"):
            values = np.stack(data[key])[rows].astype(float)
            entry[key] = {"head": values[:3].tolist(), "tail": values[-3:].tolist(), "mean": values.mean(0).tolist()}
        out[str(e)] = entry
    return out


@pytest.mark.slow
def test_recording_gives_the_frames_it_gave_before_the_loops_were_one(tmp_path):
    from colorsort.data.collect import collect
    from colorsort.data.config import CollectConfig

    out = tmp_path / "d"
    collect(CollectConfig(episodes=2, boxes_per_episode=2, cameras=(), out=str(out)), progress=False,
            log=lambda s: None)
    now, golden = frames_summary(out), json.loads(GOLDEN.read_text())["recording"]
    assert {e: v["frames"] for e, v in now.items()} == {e: v["frames"] for e, v in golden.items()}
    for e, entry in golden.items():
        for key in ("action", "observation.state"):
            for part in ("head", "tail", "mean"):
                np.testing.assert_allclose(now[e][key][part], entry[key][part], atol=1e-4)
