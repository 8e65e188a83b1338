"""How fast may a box move under the cup and still be sealed and lifted? Measured, not assumed.

    python benchmarks/bench_seal.py --speeds 0.02,0.05,0.1,0.2,0.3,0.5

For each relative speed v [m/s] the belt (a tracking belt, which never stops) runs at v and the
cup, held still over the belt, comes down onto a box as the tracking expert of version 1 did
(``studies/seal_trial.dip_heights``: down 4.3 cm in 0.2 s with suction on, 0.05 s on the box, up until the box's
bottom is 5 cm over the belt in 0.15 s), the box timed to arrive under it as the pad lands.
Printed per speed: whether the vacuum sealed, whether the box came up with the cup, the box's
offset from the cup's axis once lifted [mm] and its tilt [deg].
The tracking expert matches the belt's velocity, so the relative speed it seals at is its
matching error (millimetres per second); this is the margin it has.
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("MUJOCO_GL", "egl")

from studies.seal_trial import trial  # noqa: E402

from colorsort.results import recorded  # noqa: E402


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--speeds", default="0.02,0.05,0.1,0.2,0.3,0.5", help="relative speeds [m/s], comma-separated")
    p.add_argument("--robot", default="IRB140")
    args = p.parse_args()
    print("| box speed under the cup [m/s] | sealed | lifted | offset from the cup axis [mm] | turned [deg] |")
    print("| --- | --- | --- | --- | --- |")
    for v in (float(s) for s in args.speeds.split(",")):
        r = trial(v, args.robot)
        print(f"| {v:.2f} | {'yes' if r['sealed'] else 'no'} | {'yes' if r['lifted'] else 'no'} "
              f"| {r['offset_mm']:.0f} | {r['turn_deg']:.1f} |", flush=True)


if __name__ == "__main__":
    with recorded(__file__):
        main()
