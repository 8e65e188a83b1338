"""How long the two commands take on a fresh clone: ``bash .ci/run`` (install, lint, the whole suite),
``make test-fast`` after it, and ``make demo`` on a clone of its own.

    python benchmarks/bench_ci.py

Clones the checkout's committed HEAD twice into a temporary folder (``git clone``, no working-tree changes),
runs each command there as CI and a new user would, and prints each one's wall time, exit status and pytest's
summary line. The package caches of this machine (pip's, uv's) are as they are: on a machine that has never
downloaded the stack, add the downloads. Warp's kernel cache starts empty (``WARP_CACHE_PATH`` a new folder
inside the run), as on a fresh machine: the batched cell's tests compile MuJoCo Warp's kernels. The suite's time
is what the issue's 12-minute budget is held to.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # colorsort.results without an installed package

from colorsort.results import recorded  # noqa: E402

REPO = Path(__file__).resolve().parents[1]


def timed(command: str, cwd: Path, warp_cache: Path) -> tuple[float, int, str]:
    """(wall time [s], exit status, its output) of ``command`` run by bash in ``cwd``, Warp's kernels cached in
    ``warp_cache``."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("VIRTUAL_ENV", "PYTEST"))}
    env["WARP_CACHE_PATH"] = str(warp_cache)
    started = time.perf_counter()
    done = subprocess.run(["bash", "-c", command], cwd=cwd, env=env, capture_output=True, text=True)
    return time.perf_counter() - started, done.returncode, done.stdout + done.stderr


def summary(output: str) -> str:
    """pytest's last summary line (``N passed ... in S s``), or the output's last line."""
    found = re.findall(r"^=*\s*(\d+ (?:passed|failed).*?)\s*=*$", output, re.M)
    return found[-1] if found else output.strip().splitlines()[-1] if output.strip() else ""


def main() -> None:
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True,
                            check=True).stdout.strip()
    print(f"fresh clones of {commit}")
    print("| command | wall time | exit | result |")
    print("| --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        ci, demo = Path(tmp) / "ci", Path(tmp) / "demo"
        for clone in (ci, demo):
            subprocess.run(["git", "clone", "-q", str(REPO), str(clone)], check=True)
        for command, cwd in (("bash .ci/run", ci), ("make test-fast", ci), ("make demo", demo)):
            seconds, status, output = timed(command, cwd, Path(tmp) / f"warp-cache-{cwd.name}")
            minutes, rest = divmod(round(seconds), 60)
            result = summary(output) if "test" in command or "ci" in command else "demo outputs written" \
                if status == 0 else output.strip().splitlines()[-1]
            print(f"| `{command}` | {minutes} min {rest} s | {status} | {result} |", flush=True)


if __name__ == "__main__":
    with recorded(__file__):
        main()
