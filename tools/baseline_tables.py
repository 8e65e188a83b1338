"""Rewrite the baseline tables in README.md and docs/ from each shipped baseline's scores.json.

    python tools/baseline_tables.py [--check]

A page marks a table with ``<!-- scores baselines/<name> table|curve -->`` ... ``<!-- end scores -->``
(``colorsort.training.publishing.tables``); everything between is replaced. ``--check`` changes nothing and
exits 1 when a page differs from what its JSON gives.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from colorsort.training.publishing.tables import fill_baseline_tables, pages

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--check", action="store_true", help="report stale pages instead of rewriting them")
    args = p.parse_args()
    stale = []
    for page in pages(ROOT):
        text = page.read_text()
        new = fill_baseline_tables(text, ROOT, page)
        if new != text:
            stale.append(page.relative_to(ROOT))
            if not args.check:
                page.write_text(new)
    verb = "stale" if args.check else "rewrote"
    print(f"{verb}: {', '.join(map(str, stale))}" if stale else "every scores table is up to date")
    return 1 if stale and args.check else 0


if __name__ == "__main__":
    sys.exit(main())
