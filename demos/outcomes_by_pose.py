"""How a policy's boxes fared by where they were set down: wrong bins and drops by yaw and offset.

    colorsort-eval --policy baselines/act-camera --variant jitter --episodes 20 --json outputs/jitter.json
    python demos/outcomes_by_pose.py outputs/jitter.json

Reads the ``per_episode`` boxes of ``colorsort-eval --json`` files (each box's ``offset`` [m] from the belt's
centre line and ``yaw`` [deg]) and prints, per band of |yaw| (``turned``, either way) and of the offset, how
many boxes there were and how many went into a wrong bin or were dropped. Where the files have how the cup
held each box (``grip_offset`` [m] off the cup's axis, ``grip_yaw`` [deg] against the cup), the same per
band of those, over the boxes that were picked, with the median and 90th percentile of each.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

YAW_BANDS = ((0.0, 15.0), (15.0, 30.0), (30.0, 45.0))  # [deg] |yaw|
OFFSET_BANDS = ((-0.05, -0.025), (-0.025, 0.0), (0.0, 0.025), (0.025, 0.05))  # [m], + toward the bins
GRIP_OFFSET_BANDS = ((0.0, 0.005), (0.005, 0.01), (0.01, 0.02), (0.02, 0.06))  # [m] off the cup's axis
GRIP_YAW_BANDS = ((0.0, 5.0), (5.0, 15.0), (15.0, 45.0))  # [deg] |turn| against the cup


def bands(boxes: list[dict], key: str, edges: tuple[tuple[float, float], ...], scale: float, unit: str) -> list[str]:
    """One Markdown row per band of ``key`` (the last band closed at its top): boxes, wrong bin, dropped."""
    rows = []
    for k, (lo, hi) in enumerate(edges):
        last = k == len(edges) - 1
        inside = [b for b in boxes if lo <= b[key] < hi or (last and b[key] == hi)]
        wrong = sum(b["outcome"] == "misplaced" for b in inside)
        dropped = sum(b["outcome"] == "dropped" for b in inside)
        share = f"{100 * wrong / len(inside):.0f}%" if inside else "-"
        band = f"{key} {lo * scale:g} to {hi * scale:g} {unit}"
        rows.append(f"| {band} | {len(inside)} | {wrong} ({share}) | {dropped} |")
    return rows


def spread(boxes: list[dict], key: str, scale: float, unit: str) -> str:
    """``key``'s median and 90th percentile over ``boxes``, scaled to ``unit``."""
    values = sorted(b[key] * scale for b in boxes)
    def at(q: float) -> float:
        return values[min(len(values) - 1, round(q * (len(values) - 1)))]
    return f"{key} median {at(0.5):.1f} {unit}, 90th percentile {at(0.9):.1f} {unit}"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("evals", nargs="+", type=Path, help="colorsort-eval --json files")
    args = p.parse_args()
    boxes = [b for f in args.evals for e in json.loads(f.read_text())["per_episode"] for b in e["boxes"]
             if b["outcome"] in ("placed", "misplaced", "dropped")]
    if not boxes or "yaw" not in boxes[0]:
        raise SystemExit("no boxes with offset and yaw: write the files with this version's colorsort-eval --json")
    for b in boxes:
        b["turned"] = abs(b["yaw"])
    print(f"{len(boxes)} boxes of {', '.join(map(str, args.evals))}")
    print("| band | boxes | in a wrong bin | dropped |")
    print("| --- | --- | --- | --- |")
    print("\n".join(bands(boxes, "turned", YAW_BANDS, 1, "deg") + bands(boxes, "offset", OFFSET_BANDS, 100, "cm")))
    picked = [b for b in boxes if b.get("grip_offset") is not None]
    if picked:
        for b in picked:
            b["gripped off axis"], b["gripped turned"] = b["grip_offset"], abs(b["grip_yaw"])
        held = f"{spread(picked, 'gripped off axis', 1000, 'mm')}; {spread(picked, 'gripped turned', 1, 'deg')}"
        print(f"\nhow the cup held the {len(picked)} boxes it picked: {held}")
        print("| band | boxes | in a wrong bin | dropped |")
        print("| --- | --- | --- | --- |")
        print("\n".join(bands(picked, "gripped off axis", GRIP_OFFSET_BANDS, 1000, "mm")
                        + bands(picked, "gripped turned", GRIP_YAW_BANDS, 1, "deg")))


if __name__ == "__main__":
    main()
