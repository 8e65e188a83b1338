"""Replay a recorded episode: re-render it from its states, re-run its actions, and check both.

Example::

    colorsort-replay datasets/colorsort --episode 0 --camera scene --size 480x640 \\
        --video outputs/replay.mp4 --sheet outputs/replay.png

*State replay* restores each frame's ``sim_state`` and renders ``--camera`` at ``--size`` into
an mp4 (and a contact sheet PNG). The restored state must give back the recorded
``observation.state`` and ``observation.environment_state`` exactly, and when that camera was
recorded at that size, every re-rendered frame is compared with the dataset's decoded frame
(they differ only by the video codec's loss: LeRobot encodes at crf 30).
*Action replay* restores the first frame's state and steps the recorded actions: the episode
must end the same way (every box in the bin of its colour, or let through), and the states it
passes through are compared with the recorded ones. Exit status 0 when both checks pass,
1 when one fails, 2 for bad arguments.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from colorsort.cell.cameras import CAMERAS
from colorsort.cli.args import parse_image_size
from colorsort.cli.run import guarded
from colorsort.data.replay import MIN_PSNR_DB, replay
from colorsort.errors import FAILED
from colorsort.logs import quiet_robosuite_info


@guarded("colorsort-replay")
def main(argv: list[str] | None = None) -> int:
    quiet_robosuite_info()
    # datasets' note when HF_DATASETS_DISABLE_PROGRESS_BARS is set, and torchvision's deprecation notice
    warnings.filterwarnings("ignore", message="Cannot enable progress bars")
    warnings.filterwarnings("ignore",
                            message="The video decoding and encoding capabilities of torchvision are deprecated")
    parser = argparse.ArgumentParser(prog="colorsort-replay", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dataset", help="dataset directory (colorsort-collect's --out)")
    parser.add_argument("--episode", type=int, default=0, help="episode index")
    parser.add_argument("--camera", default="scene", choices=list(CAMERAS), help="camera to render")
    parser.add_argument("--size", default=None, help="HxW or a square size [px]; default: the recorded size")
    parser.add_argument("--video", default=None, help="mp4 path (default outputs/replay_ep<I>_<camera>.mp4)")
    parser.add_argument("--sheet", default=None, help="contact sheet PNG path (default: the video's, .png)")
    args = parser.parse_args(argv)
    size = parse_image_size(args.size) if args.size else None
    video = args.video or f"outputs/replay_ep{args.episode}_{args.camera}.mp4"
    sheet = args.sheet or str(Path(video).with_suffix(".png"))
    report = replay(args.dataset, args.episode, args.camera, size, video, sheet)
    print(f"episode {args.episode}: {report.frames} frames -> {report.video}, contact sheet {report.sheet}")
    print(f"state replay: {report.frames - report.state_mismatches}/{report.frames} restored states give back "
          "the recorded observation.state and environment_state exactly")
    if report.min_psnr_db is None:
        print(f"state replay: {args.camera} at this size is not in the dataset, no frames to compare")
    else:
        print(f"state replay: re-rendered vs recorded frames: min PSNR {report.min_psnr_db:.1f} dB "
              f"(pass >= {MIN_PSNR_DB:.0f}), mean abs error {report.mean_abs_error:.2f} levels")
    print(f"state replay -> {'ok' if report.state_replay_ok else 'FAILED'}")
    print(f"action replay: outcomes {report.outcomes}, max qpos deviation {report.max_state_error:.2e} "
          f"-> {'ok' if report.action_replay_ok else 'FAILED'}")
    return 0 if report.state_replay_ok and report.action_replay_ok else FAILED


if __name__ == "__main__":
    sys.exit(main())
