"""Does a camera policy's image encoder see where a box is? A linear probe of its features.

    python demos/probe_features.py --policy baselines/act-camera [--data DATASET] [--camera sensor] [--random-init]

``DATASET`` is a ``colorsort-collect`` dataset recorded with the policy's cameras and image size
(its ``observation.environment_state`` holds each box's colour and pose); without ``--data`` the
script records one first, in a temporary folder: ``colorsort-collect --variant jitter --episodes
12 --boxes-per-episode 3 --seed 9000000`` (seeds no training set or evaluation uses) with the
policy's cameras and image size. The first frames in
which each box blocks the ray (the arm at its wait pose, the box in the sensor camera's full view)
are passed through the policy's own preprocessor and image encoder (ACT: the ResNet-18's last
feature map, flattened; diffusion: the spatial-softmax keypoints, after the centre crop), and a
ridge regression from those features is fitted on the even episodes and scored on the odd ones
(held-out boxes) for the box's offset across the belt [cm], its turn (as the point cos 4 yaw,
sin 4 yaw: a cube turned by 90 deg looks the same) and its colour (accuracy of the largest of
three regressions). The same probe on the raw normalised pixels says what the image itself
holds; ``--random-init`` probes the same encoder with fresh random weights (what training
added). A held-out R^2 near 1 means the features give the box's place; near 0 or below, they
do not.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("HF_HUB_OFFLINE", "1")

import numpy as np  # noqa: E402
import torch  # noqa: E402

from colorsort.benchmark.policies import LeRobotPolicy, checkpoint_cameras  # noqa: E402
from colorsort.config import COLORS  # noqa: E402
from colorsort.data.schema import env_state_names  # noqa: E402
from colorsort.results import recorded  # noqa: E402

FIRST = 5  # frames probed per box, from the one in which it blocks the ray [control steps of 50 ms]
RIDGE = (1e-3, 1e-2, 1e-1, 1, 10, 100, 1e3, 1e4)  # penalties tried, chosen on the training episodes


def encoder(policy: LeRobotPolicy, camera: str):
    """The policy's image features of a preprocessed (B, 3, H, W) batch as (B, D)."""
    model = policy.policy
    if policy.policy.config.type == "act":
        return lambda x: model.model.backbone(x)["feature_map"].flatten(1)
    rgb = model.diffusion.rgb_encoder
    if isinstance(rgb, torch.nn.ModuleList):  # one encoder per camera, in the config's order
        cameras = [k.removeprefix("observation.images.") for k in model.config.image_features]
        rgb = rgb[cameras.index(camera)]
    crop = rgb.center_crop if rgb.do_crop else (lambda x: x)
    return lambda x: rgb.pool(rgb.backbone(crop(x))).flatten(1)


def frames(data: Path, camera: str, policy: LeRobotPolicy) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
    """(preprocessed images, targets, episode index) of the first ``FIRST`` frames after each box reached the ray:
    the arm still at its wait pose, the box in full view of the sensor camera (the descending arm hides it)."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    ds = LeRobotDataset("local/probe", root=data, video_backend="pyav")
    names = ds.meta.features["observation.state"]["names"]
    ray, sealed = names.index("ray.blocked"), names.index("suction.sealed")
    images, env, episodes = [], [], []
    waited, last_episode = 0, -1
    for i in range(len(ds)):
        item = ds[i]
        state = item["observation.state"]
        episode = int(item["episode_index"])
        blocked = state[ray] > 0.5 and state[sealed] < 0.5 and item["observation.environment_state"][-1] > 0.5
        waited = waited + 1 if blocked and episode == last_episode else int(blocked)
        last_episode = episode
        if not 1 <= waited <= FIRST:
            continue
        batch = {"observation.state": state[None], "task": [""],
                 **{k: item[k][None] for k in item if k.startswith("observation.images.")}}
        images.append(policy.preprocessor(batch)[f"observation.images.{camera}"][0])
        env.append(item["observation.environment_state"].numpy())
        episodes.append(episode)
    e = np.array(env)
    at = {name: k for k, name in enumerate(env_state_names())}
    w, x, y, z = (e[:, at[f"box.q{c}"]] for c in "wxyz")  # the box's turn about the vertical
    yaw = np.degrees(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
    colours = e[:, [at[f"box.is_{c}"] for c in COLORS]].argmax(1)
    targets = {"offset_cm": 100 * e[:, at["box.y"]], "turn": np.radians(4 * yaw), "colour": colours}
    return torch.stack(images).numpy(), targets, np.array(episodes)


def ridge(x: np.ndarray, y: np.ndarray, lam: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ridge regression of ``y`` on ``x`` with penalty ``lam``; the means are fitted unpenalised."""
    mx, my = x.mean(0), y.mean(0)
    xc = x - mx
    if len(x) < x.shape[1]:  # fewer frames than features: the same solution from the frames' side
        return xc.T @ np.linalg.solve(xc @ xc.T + lam * np.eye(len(x)), y - my), mx, my
    return np.linalg.solve(xc.T @ xc + lam * np.eye(x.shape[1]), xc.T @ (y - my)), mx, my


def predict(fit: tuple[np.ndarray, np.ndarray, np.ndarray], x: np.ndarray) -> np.ndarray:
    w, mx, my = fit
    return (x - mx) @ w + my


def probe(features: np.ndarray, targets: dict[str, np.ndarray], episodes: np.ndarray) -> dict[str, float]:
    """Held-out R^2 of offset and turn and colour accuracy; the penalty chosen by leave-one-episode-out on the
    training (even) episodes."""
    train, test = episodes % 2 == 0, episodes % 2 == 1
    spread = features[train].std(0)
    keep = spread > 1e-6  # a feature constant over the training frames says nothing (and would divide by 0)
    f = (features[:, keep] - features[train][:, keep].mean(0)) / spread[keep]
    out = {}
    for key, y in targets.items():
        if key == "colour":
            y2 = np.eye(int(y.max()) + 1)[y]
        else:  # a cube looks the same turned by 90 deg: its turn as the point (cos 4 yaw, sin 4 yaw)
            y2 = np.stack([np.cos(y), np.sin(y)], 1) if key == "turn" else y[:, None]

        def score(w: tuple, rows: np.ndarray, key: str = key, y2: np.ndarray = y2) -> float:
            p = predict(w, f[rows])
            if key == "colour":
                return float((p.argmax(1) == y2[rows].argmax(1)).mean())
            return float(1 - ((p - y2[rows]) ** 2).sum() / ((y2[rows] - y2[rows].mean(0)) ** 2).sum())

        def cv(lam: float, y2: np.ndarray = y2, score=score) -> float:
            held = []
            for ep in np.unique(episodes[train]):
                fit = train & (episodes != ep)
                held.append(score(ridge(f[fit], y2[fit], lam), train & (episodes == ep)))
            return float(np.mean(held))

        lam = max(RIDGE, key=cv)
        out[key] = score(ridge(f[train], y2[train], lam), test)
    return out


def record(policy: str, out: Path) -> Path:
    """12 jitter demos at the policy's cameras and image size, of seeds no training set or evaluation uses."""
    cameras, size = checkpoint_cameras(policy)
    if size is None:
        raise SystemExit(f"{policy} reads no camera: nothing to probe")
    subprocess.run([str(Path(sys.executable).parent / "colorsort-collect"), "--variant", "jitter", "--episodes", "12",
                    "--boxes-per-episode", "3", "--seed", "9000000", "--cameras", ",".join(cameras), "--image-size",
                    str(size[0]), "--workers", "2", "--out", str(out), "--repo-id", "local/probe"],
                   check=True, stdout=subprocess.DEVNULL)
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--policy", required=True, help="a LeRobot camera policy's pretrained_model folder")
    p.add_argument("--data", type=Path, help="a colorsort-collect dataset at the policy's image size "
                                             "(default: 12 jitter demos recorded first)")
    p.add_argument("--camera", default="sensor", help="the camera whose images are probed")
    p.add_argument("--random-init", action="store_true", help="also probe the same encoder with random weights")
    args = p.parse_args()
    torch.manual_seed(0)
    policy = LeRobotPolicy(args.policy)
    with tempfile.TemporaryDirectory() as tmp:
        data = args.data or record(args.policy, Path(tmp) / "jitter")
        images, targets, episodes = frames(data, args.camera, policy)
    with torch.no_grad():
        rows = [("raw pixels", images.reshape(len(images), -1)),
                ("trained encoder", encoder(policy, args.camera)(torch.from_numpy(images)).numpy())]
        if args.random_init:
            fresh = type(policy.policy)(policy.policy.config)
            policy.policy = fresh.eval()
            rows.append(("random encoder", encoder(policy, args.camera)(torch.from_numpy(images)).numpy()))
    boxes = len({(e, round(float(o), 1)) for e, o in zip(episodes, targets["offset_cm"], strict=True)})
    with recorded(__file__):
        print(f"{args.policy}, camera {args.camera}: {len(images)} frames of about {boxes} boxes waiting at the ray "
              f"in {args.data or 'jitter demos of seeds 9000000..'} ({len(np.unique(episodes))} episodes; "
              "fitted on the even ones, scored on the odd)")
        print("| features | size | offset R^2 (held out) | turn R^2 (held out) | colour accuracy (held out) |")
        print("| --- | --- | --- | --- | --- |")
        for name, feats in rows:
            s = probe(feats, targets, episodes)
            print(f"| {name} | {feats.shape[1]} | {s['offset_cm']:.2f} | {s['turn']:.2f} | {s['colour']:.2f} |")


if __name__ == "__main__":
    main()
