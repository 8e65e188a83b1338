"""Rewrite the held-out shift tables (README.md, docs/shifts.md, docs/shift_results.md, and each sweep's page of
every arm, docs/results/shifts/<policy>-<variant>.md) and heatmap from the sweeps in docs/results/shifts/.

    python tools/shift_tables.py [--add outputs/sweeps/SWEEP.json ...] [--check] [--out DIR]

``--add`` keeps a sweep's summary (``colorsort-eval --sweep --json``) as docs/results/shifts/<policy>-<variant>.json
first. ``--out DIR`` writes the table (DIR/shifts.md) and the heatmap (DIR/shift_heatmap.png) there instead of the
pages. ``--check`` changes nothing and exits 1 when a page differs from what the summaries give.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from colorsort.benchmark.shift_tables import (
    fill_shift_tables,
    full_table,
    heatmap,
    load,
    shifts_headline,
    summary,
    sweep_name,
    sweep_page,
)

ROOT = Path(__file__).resolve().parent.parent
SUMMARIES = ROOT / "docs" / "results" / "shifts"
PAGES = (ROOT / "README.md", ROOT / "docs" / "shifts.md", ROOT / "docs" / "shift_results.md")
HEATMAP = ROOT / "docs" / "img" / "shift_heatmap.png"


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--add", nargs="*", default=[], help="sweep JSON files to keep as summaries first")
    p.add_argument("--from", dest="source", default=str(SUMMARIES), help="the folder of summaries to read")
    p.add_argument("--out", default=None, help="write DIR/shifts.md and DIR/shift_heatmap.png instead of the pages")
    p.add_argument("--check", action="store_true", help="report stale pages instead of rewriting them")
    args = p.parse_args()
    source = Path(args.source)
    for path in args.add:
        sweep = summary(json.loads(Path(path).read_text()))  # its rows recomputed from its reports
        source.mkdir(parents=True, exist_ok=True)
        (source / f"{sweep_name(sweep)}.json").write_text(json.dumps(sweep, indent=1) + "\n")
    sweeps = load(source)
    if not sweeps:
        print(f"no sweep summaries in {source}", file=sys.stderr)
        return 1
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "shifts.md").write_text(shifts_headline(sweeps) + "\n\n" + full_table(sweeps) + "\n")
        heatmap(sweeps, out / "shift_heatmap.png")
        print(f"wrote {out / 'shifts.md'}, {out / 'shift_heatmap.png'}")
        return 0
    stale = []
    pages = {page: fill_shift_tables(page.read_text(), sweeps) for page in PAGES}
    pages |= {source / f"{sweep_name(s)}.md": sweep_page(s) for s in sweeps}  # every arm of each sweep
    for page, new in pages.items():
        text = page.read_text() if page.exists() else ""
        if new != text:
            stale.append(page.relative_to(ROOT) if page.is_relative_to(ROOT) else page)
            if not args.check:
                page.write_text(new)
    if not args.check:
        heatmap(sweeps, HEATMAP)
    verb = "stale" if args.check else "rewrote"
    print(f"{verb}: {', '.join(map(str, stale))}" if stale else "every shift table is up to date")
    return 1 if stale and args.check else 0


if __name__ == "__main__":
    sys.exit(main())
