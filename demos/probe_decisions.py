"""Count a stopping-belt demo set's decision frames: a box at the ray, the belt stopped, the arm still.

At such a frame a policy decides between picking the box and letting it through, and it can tell
them apart only by the box's colour. Under ACT's L1 loss the label it learns for a colour it does
not yet tell apart from another is the more frequent one, so the two counts printed here should
not be far apart (``colorsort.data.late_pass`` and ``colorsort.data.late_pick`` set them)::

    python demos/probe_decisions.py outputs/baselines/snap-dim/data/demos-48-lit0.45-0.75-late100

A frame counts as a pass when the belt-pass command comes on within the next ``--horizon`` stored
actions, as a pick when instead the joint targets move more than 0.01 rad from the arm's angles.
"""

from __future__ import annotations

import argparse
import glob
import json
from pathlib import Path

import numpy as np

MOVED = 0.01  # [rad] joint targets this far from the arm's angles: the arm is sent somewhere


def decision_counts(root: Path, horizon: int = 10) -> dict[str, int]:
    """{"decision": frames at the ray with the arm still, "pass": those followed by belt-pass, "pick": by
    an arm motion, "neither"} of the LeRobot dataset at ``root`` (its ``observation.state`` names the
    ray, belt, suction and joint velocities)."""
    import pandas as pd

    info = json.loads((root / "meta" / "info.json").read_text())
    names = info["features"]["observation.state"]["names"]
    actions = info["features"]["action"]["names"]
    df = pd.concat(pd.read_parquet(f) for f in sorted(glob.glob(str(root / "data" / "*" / "*.parquet"))))
    state, act = np.stack(df["observation.state"].to_numpy()), np.stack(df["action"].to_numpy())
    episode = df["episode_index"].to_numpy()
    col = names.index
    joints = [i for i, n in enumerate(names) if n.endswith(".pos") and n.startswith("joint_")]
    speeds = [i for i, n in enumerate(names) if n.endswith(".vel") and n.startswith("joint_")]
    still = np.abs(state[:, speeds]).max(axis=1) < 1e-3
    waiting = (state[:, col("ray.blocked")] > 0.5) & (state[:, col("belt.running")] < 0.5)
    waiting &= (state[:, col("suction.on")] < 0.5) & still
    belt_pass, targets = actions.index("belt_pass"), [actions.index(n.replace(".pos", ".target")) for n in
                                                       (names[i] for i in joints)]
    counts = {"decision": int(waiting.sum()), "pass": 0, "pick": 0, "neither": 0}
    for i in np.flatnonzero(waiting):
        ahead = np.arange(i, min(i + horizon, len(df)))
        ahead = ahead[episode[ahead] == episode[i]]
        if act[ahead, belt_pass].max() > 0.0:
            counts["pass"] += 1
        elif np.abs(act[ahead][:, targets] - state[i, joints]).max() > MOVED:
            counts["pick"] += 1
        else:
            counts["neither"] += 1
    return counts


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("roots", nargs="+", type=Path, help="LeRobot dataset folders (stopping-belt demos)")
    p.add_argument("--horizon", type=int, default=10, help="stored actions looked ahead [control steps]")
    args = p.parse_args()
    for root in args.roots:
        c = decision_counts(root, args.horizon)
        print(f"{root}: {c['decision']} decision frames: {c['pick']} start a pick, {c['pass']} a pass, "
              f"{c['neither']} neither")


if __name__ == "__main__":
    main()
