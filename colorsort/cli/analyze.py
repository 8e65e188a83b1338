"""Analyses of evaluations and baselines: ``colorsort-eval --json`` files and ``scores.json``.

Example::

    colorsort-eval --policy baselines/act-camera-snapshot --variant jitter --episodes 20 --json outputs/jitter.json
    colorsort-analyze by-pose outputs/jitter.json          # wrong bins and drops by the box's yaw and offset
    colorsort-analyze by-lights outputs/lights.json        # lighting episodes by the brightness they drew
    colorsort-analyze by-lights --demos datasets/lighting  # the brightness each demo was recorded under
    colorsort-analyze first-box-delay new.json old.json    # how much later one policy places its first box
    colorsort-analyze compare new/scores.json old/scores.json --labels new,old  # two baseline runs per variant
    colorsort-analyze curves a/scores.json b/results.json --labels ACT,Diffusion --out curves.png  # one axis

Exit status 0, or 2 for files that cannot be compared (their message says why).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from colorsort.cli.run import guarded
from colorsort.errors import ConfigError


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="colorsort-analyze", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="analysis", required=True)
    pose = sub.add_parser("by-pose", help="boxes by where they were set down and how the cup held them")
    pose.add_argument("evals", nargs="+", type=Path, help="colorsort-eval --json files")
    lights = sub.add_parser("by-lights", help="lighting episodes by the brightness of their lights")
    lights.add_argument("evals", nargs="*", type=Path, help="colorsort-eval --json files of one variant")
    lights.add_argument("--demos", type=Path, help="a colorsort-collect dataset: the brightness of each episode")
    delay = sub.add_parser("first-box-delay", help="NEW's first placed box minus OLD's, median over shared seeds")
    delay.add_argument("new", type=Path)
    delay.add_argument("old", type=Path)
    compare = sub.add_parser("compare", help="two baseline runs' scores.json side by side per variant")
    compare.add_argument("new", type=Path)
    compare.add_argument("old", type=Path)
    compare.add_argument("--labels", default="new,old", help="two comma-separated column labels")
    curves = sub.add_parser("curves", help="baseline runs' learning curves on one axis: success against training time")
    curves.add_argument("scores", nargs="+", type=Path, help="scores.json or results.json files, one curve each")
    curves.add_argument("--labels", required=True, help="comma-separated, one label per file")
    curves.add_argument("--out", type=Path, required=True, help="the PNG to write")
    return p


def read(path: Path) -> dict:
    return json.loads(path.read_text())


def plot_runs(files: list[Path], labels: list[str], out: Path) -> None:
    """Each run's learning curve (its first seed's checkpoints on its main variant) on one axis, written to ``out``."""
    from colorsort.training.publishing.run_summary import plot_curves
    from colorsort.training.publishing.tables import main_variant, trained_on
    from colorsort.training.results_file import PipelineResults

    if len(labels) != len(files):
        raise ConfigError(f"--labels takes one label per file: {len(files)} files, {len(labels)} labels")
    runs = [PipelineResults.load(f) for f in files]
    if missing := [str(f) for f, r in zip(files, runs, strict=True) if not r.curve]:
        raise ConfigError(f"no learning curve in {', '.join(missing)}")
    variants = {main_variant(r) for r in runs}
    if len(variants) > 1:
        raise ConfigError(f"the curves are on different variants ({', '.join(sorted(variants))}); give runs of one")
    machines = sorted({trained_on(r) for r in runs})
    plot_curves([(lab, r.curve) for lab, r in zip(labels, runs, strict=True)], variants.pop(),
                " / ".join(machines), out)
    each = (f"{lab} ({len(r.curve)} checkpoints)" for lab, r in zip(labels, runs, strict=True))
    print(f"wrote {out}: {', '.join(each)}")


@guarded("colorsort-analyze")
def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    if args.analysis == "by-pose":
        from colorsort.benchmark.outcomes import pose_report

        print("\n".join(pose_report([read(f) for f in args.evals])))
    elif args.analysis == "by-lights":
        from colorsort.benchmark.outcomes import demo_brightness, lights_report

        if args.demos is not None:
            values = demo_brightness(args.demos)
            print(f"{len(values)} episodes of {args.demos}, brightness: {', '.join(f'{b:.2f}' for b in values)}")
        elif args.evals:
            print("\n".join(lights_report([read(f) for f in args.evals])))
        else:
            raise ConfigError("by-lights: give colorsort-eval --json files, or --demos ROOT")
    elif args.analysis == "first-box-delay":
        from colorsort.benchmark.outcomes import first_box_delay

        new, old = read(args.new), read(args.old)
        median, seeds = first_box_delay(new, old)
        print(f"first box placed {median:+.2f} s later (median over {seeds} seeds, {new['variant']}); "
              f"mean cycle {new['mean_cycle_time_s']:.2f} s against {old['mean_cycle_time_s']:.2f} s")
    elif args.analysis == "curves":
        plot_runs(args.scores, args.labels.split(","), args.out)
    else:
        from colorsort.training.publishing.compare import compare
        from colorsort.training.results_file import PipelineResults

        labels = tuple(args.labels.split(","))
        if len(labels) != 2:
            raise ConfigError(f"--labels takes two comma-separated labels, got {args.labels!r}")
        print(compare(PipelineResults.load(args.new), PipelineResults.load(args.old), (labels[0], labels[1])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
