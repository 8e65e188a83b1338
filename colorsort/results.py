"""Benchmark figures as files: what a script printed, with its command, the machine and the date.

Every ``benchmarks/*.py`` runs its ``main`` inside ``recorded(__file__)``: the output is printed as
usual and also written to ``docs/results/<script>[_<arguments>].md``, which the docs pages link
instead of retyping numbers. ``COLORSORT_RESULTS`` names another folder, or ``none`` for no file
(the tests run scripts that way).
"""

from __future__ import annotations

import datetime as dt
import io
import os
import platform
import re
import shlex
import shutil
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TextIO

REPO = Path(__file__).resolve().parent.parent
RESULTS = REPO / "docs" / "results"


def this_machine() -> str:
    """This machine in a line: CPU model, cores, memory, OS, Python, GPU."""
    cpu = platform.processor() or platform.machine()
    try:
        text = Path("/proc/cpuinfo").read_text()
        cpu = re.search(r"model name\s*:\s*(.+)", text)[1].strip()  # type: ignore[index]
    except (OSError, TypeError):
        pass
    memory = ""
    try:
        kib = int(re.search(r"MemTotal:\s*(\d+)", Path("/proc/meminfo").read_text())[1])  # type: ignore[index]
        memory = f", {kib / 2**20:.0f} GiB"
    except (OSError, TypeError):
        pass
    gpu = "a GPU (nvidia-smi)" if shutil.which("nvidia-smi") else "no GPU"
    return (f"{cpu}, {os.cpu_count()} cores{memory}, {platform.system()} {platform.release()}, "
            f"Python {platform.python_version()}, {gpu}")


def results_path(script: str, argv: list[str]) -> Path | None:
    """Where ``script`` run with ``argv`` writes its figures (None: nowhere)."""
    folder = os.environ.get("COLORSORT_RESULTS", str(RESULTS))
    if folder.lower() == "none":
        return None
    slug = re.sub(r"[^A-Za-z0-9.,]+", "-", " ".join(argv)).strip("-")
    return Path(folder) / (Path(script).stem + (f"_{slug}" if slug else "") + ".md")


class _Tee(io.TextIOBase):
    def __init__(self, stream: TextIO):
        self.stream, self.copy = stream, io.StringIO()

    def write(self, text: str) -> int:
        self.copy.write(text)
        return self.stream.write(text)

    def flush(self) -> None:
        self.stream.flush()


@contextmanager
def recorded(script: str, argv: list[str] | None = None) -> Iterator[None]:
    """Print as usual; at the end (if nothing raised) write everything printed to ``results_path``."""
    argv = sys.argv[1:] if argv is None else argv
    path = results_path(script, argv)
    started = dt.datetime.now(dt.UTC)
    tee, stdout = _Tee(sys.stdout), sys.stdout
    sys.stdout = tee
    try:
        yield
    finally:
        sys.stdout = stdout
    if path is None:
        return
    command = shlex.join(["python", f"benchmarks/{Path(script).name}", *argv])
    minutes = (dt.datetime.now(dt.UTC) - started).total_seconds() / 60
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f"# `{command}`\n\nWritten by the command above on {started:%Y-%m-%d %H:%M} UTC "
                    f"({minutes:.1f} min), on: {this_machine()}.\n\n```\n{tee.copy.getvalue().rstrip()}\n```\n")
    print(f"figures: {path.relative_to(REPO) if path.is_relative_to(REPO) else path}")
