"""A screenshot of a ``colorsort-eval --report`` page, taken by headless Chromium (for the docs).

    python tools/report_screenshot.py outputs/report docs/img/report.png

The first video is played for a moment and paused at ``--at`` seconds, so that the picture shows
a frame of the episode rather than a blank player. Needs Debian's ``chromium`` (or ``--browser``)
and Playwright (the dev extra).
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from playwright.sync_api import sync_playwright


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("report", help="the folder colorsort-eval --report wrote")
    parser.add_argument("png", help="where to write the screenshot")
    parser.add_argument("--at", type=float, default=40.0, help="time of the first video's frame [s]")
    parser.add_argument("--width", type=int, default=1100, help="viewport width [px]")
    parser.add_argument("--height", type=int, default=1300, help="viewport height [px]")
    parser.add_argument("--browser", default=shutil.which("chromium") or "chromium", help="Chromium executable")
    args = parser.parse_args()
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=args.browser)
        page = browser.new_page(viewport={"width": args.width, "height": args.height})
        page.goto((Path(args.report) / "index.html").resolve().as_uri())
        page.evaluate("""async at => { const v = document.querySelector('video'); if (!v) return;
            await v.play(); v.pause(); v.currentTime = Math.min(at, v.duration);
            await new Promise(ok => v.addEventListener('seeked', ok, {once: true})); }""", args.at)
        Path(args.png).parent.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=args.png)
        browser.close()
    print(f"screenshot: {args.png}")


if __name__ == "__main__":
    main()
