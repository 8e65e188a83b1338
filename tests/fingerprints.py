"""Fingerprints of what the versioned code makes (``colorsort.versions``): short, fixed runs hashed.

    python tests/fingerprints.py            # print each part's fingerprint now
    python tests/fingerprints.py --write    # record them, with the versions they were made with

``tests/test_versions.py`` compares each with the one recorded in ``tests/data/fingerprints.json``. A part's
fingerprint also moves with the parts it runs on (the expert's with the cell's), so each is recorded with the
versions of all of them: a change of behaviour with the same versions fails the test (bump the version of the
code that changed), and a bumped version asks for the fingerprints to be recorded again.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

import colorsort  # noqa: F401 - first: the headless GL backend, robosuite's notices quieted

# isort: split
import robosuite as suite

from colorsort import versions

RECORDED = Path(__file__).parent / "data" / "fingerprints.json"
DEPENDS: dict[str, tuple[str, ...]] = {"cell": ("cell",), "expert": ("expert", "cell"),
                                       "recorder": ("recorder", "cell"), "shifts": ("shifts", "cell")}


def digest(values: object) -> str:
    """16 hex digits of the SHA-256 of ``values`` as sorted JSON."""
    return hashlib.sha256(json.dumps(values, sort_keys=True).encode()).hexdigest()[:16]


def rounded(array, step: float) -> list:
    """Values rounded to multiples of ``step``, as ints: far above float noise across machines."""
    return np.round(np.asarray(array, float) / step).astype(int).tolist()


def make(**kwargs):
    kwargs = {"has_offscreen_renderer": False, "use_camera_obs": False, "ignore_done": True, "seed": 0, **kwargs}
    return suite.make("ColorSort", robots="IRB140", **kwargs)


def cell() -> str:
    """The cell as the arm holds home for 4 s of belt, boxes arriving and the belt stopping: its state every
    second (to 0.1 mm, 1 mrad) and the box stream."""
    env = make()
    try:
        env.reset(seed=3)
        low, high = env.action_spec
        action = np.clip(np.concatenate([env.robot_spec.home, [-1.0, 1.0]]), low, high)
        states = []
        for step in range(80):
            env.step(action)
            if step % 20 == 19:
                states.append(rounded(env.get_sim_state(), 1e-4))
        boxes = [(b.serial, b.color) for b in env.boxes_in_play()]
        return digest({"states": states, "boxes": boxes, "events": [e.outcome for e in env.events]})
    finally:
        env.close()


def expert() -> str:
    """The stopping belt's expert sorting the first box of seed 0: every action (to 1 mrad) and the outcome."""
    from colorsort.expert.factory import make_expert

    env = make(has_offscreen_renderer=True, use_camera_obs=True, camera_names=["sensor"], camera_heights=32,
               camera_widths=32)
    try:
        obs = env.reset(seed=0)
        agent = make_expert(env)
        agent.reset(obs)
        actions = []
        while not env.events and env.cur_time < 20.0:
            action = agent.act(obs)
            actions.append(rounded(action, 1e-3))
            obs, _, _, _ = env.step(action)
        return digest({"actions": actions, "events": [(e.outcome, e.bin) for e in env.events]})
    finally:
        env.close()


def recorder() -> str:
    """What a recorded frame holds: the dataset's features, and the first frame's values (not its images) and
    task, on a camera dataset of the stopping belt."""
    from colorsort.envs.schema import features, frame, task_text

    env = make(has_offscreen_renderer=True, use_camera_obs=True, camera_names=["snapshot"], camera_heights=32,
               camera_widths=32)
    try:
        obs = env.reset(seed=0)
        action = np.concatenate([env.robot_spec.home, [-1.0, -1.0]])
        first = frame(env, obs, action, ("snapshot",), task_text("red", 3))
        values = {k: (rounded(v, 1e-4) if k != "task" else v) for k, v in first.items() if "images" not in k}
        shapes = {k: list(np.shape(v)) for k, v in first.items() if k != "task"}
        return digest({"features": json.loads(json.dumps(features(env, ("snapshot",), (32, 32)))),
                       "values": values, "shapes": shapes})
    finally:
        env.close()


def shifts() -> str:
    """Every shift at level 3 at once (``all:3``: each draws as it would alone) on a shift seed: the values drawn,
    the model's shifted fields (to 1e-4) and the state after 1 s of belt with the arm held at home (0.1 mm, 1 mrad);
    the camera images' shifts (noise, blur) by their drawn values."""
    from colorsort.shifts.episode import MODEL_FIELDS

    env = make(shift="all:3")
    try:
        env.reset(seed=30000)
        low, high = env.action_spec
        action = np.clip(np.concatenate([env.robot_spec.home, [-1.0, 1.0]]), low, high)
        for _ in range(20):
            env.step(action)
        model = {f: rounded(getattr(env.mj_model, f), 1e-4) for f in MODEL_FIELDS}
        drawn = json.loads(json.dumps(env.shifts.record, default=lambda v: rounded(v, 1e-4)))
        return digest({"drawn": drawn, "model": model, "state": rounded(env.get_sim_state(), 1e-4)})
    finally:
        env.close()


FINGERPRINTS: dict[str, Callable[[], str]] = {"cell": cell, "expert": expert, "recorder": recorder, "shifts": shifts}


def versions_of(part: str) -> dict[str, int]:
    """The versions ``part``'s fingerprint depends on."""
    return versions.code_versions(*DEPENDS[part])


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--write", action="store_true", help=f"record them in {RECORDED.name}")
    args = p.parse_args()
    now = {part: {"versions": versions_of(part), "fingerprint": fn()} for part, fn in FINGERPRINTS.items()}
    print(json.dumps(now, indent=1))
    if args.write:
        RECORDED.write_text(json.dumps(now, indent=1, sort_keys=True) + "\n")
        print(f"recorded in {RECORDED}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
