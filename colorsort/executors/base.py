"""One interface over the engines that run tasks: local processes and Ray.

A task is a top-level function ``fn(arg, ctx)`` and its argument, both picklable; ``ctx.send(m)``
reports progress to the caller (``on_message``), ``ctx.stopping()`` turns true when the caller was
asked to stop (Ctrl-C). An executor runs the tasks, at most ``workers`` at once; a task whose
process died (SIGKILL, out of memory, a node lost) runs again, up to ``retries`` times; an
exception raised by the task is its result, not retried (it would raise again). A stop can also come
as KeyboardInterrupt (Ray's cancel, a terminal's Ctrl-C); a task holds it back where a write must
not be cut short with ``held_interrupts()``.
"""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Protocol

from colorsort.config import check_range
from colorsort.errors import ConfigError, UnknownName

EXECUTORS = ("local", "ray")
DEFAULT_SHARD_SIZE = 32  # episodes per task: a few dozen, so a cluster merges hundreds of shards, not thousands
# Passed on to every worker, on this machine or a cluster's: rendering, offline hub, LeRobot's cache.
FORWARDED_ENV = ("MUJOCO_GL", "PYOPENGL_PLATFORM", "HF_HUB_OFFLINE", "HF_HOME", "HF_LEROBOT_HOME")


@dataclass(frozen=True)
class ExecutorConfig:
    """Which engine runs the tasks, and how many at once."""

    name: str = "local"  # "local": processes on this machine; "ray": a Ray cluster
    workers: int = 1  # tasks run at once (local: processes; ray: tasks of 1 CPU each)
    retries: int = 2  # re-runs of a task whose process died
    address: str | None = None  # ray only: a cluster to join ("auto", "ray://head:10001"); None starts one here

    def __post_init__(self) -> None:
        if self.name not in EXECUTORS:
            raise UnknownName("executor", self.name, list(EXECUTORS), "executors")
        check_range("workers", self.workers, 1, 100_000)
        check_range("retries", self.retries, 0, 100)
        if self.address is not None and self.name != "ray":
            raise ConfigError(f"address={self.address!r} is for the ray executor; got executor {self.name!r}")


@dataclass(frozen=True)
class Task:
    key: str  # names the task in errors, e.g. "shard-000032"
    fn: Callable[[Any, TaskContext], Any]  # a module-level function
    arg: Any


@dataclass
class TaskResult:
    key: str
    value: Any = None  # what fn returned
    error: str | None = None  # its traceback, or why its process died
    attempts: int = 0  # times it started
    stopped: bool = False  # the caller stopped the run (Ctrl-C) before this task returned, or before it started

    @property
    def ok(self) -> bool:
        return self.attempts > 0 and self.error is None and not self.stopped


class TaskContext(Protocol):
    def send(self, message: Any) -> None: ...

    def stopping(self) -> bool: ...


class Executor(Protocol):
    config: ExecutorConfig

    def run(self, tasks: list[Task], on_message: Callable[[Any], None] = lambda m: None,
            on_done: Callable[[TaskResult], None] = lambda r: None) -> list[TaskResult]:
        """Run ``tasks``; returns their results in the tasks' order."""
        ...


def chunks(items: list, size: int, workers: int = 1) -> list[list]:
    """``items`` in contiguous blocks of at most ``size``, and at least ``min(workers, len(items))`` blocks
    (so that a small job still keeps every worker busy), sizes differing by at most one."""
    check_range("shard size", size, 1, 1_000_000)
    parts = max(-(-len(items) // size), min(workers, len(items)))
    bounds = [len(items) * k // parts for k in range(parts + 1)] if items else [0]
    return [items[bounds[k]:bounds[k + 1]] for k in range(len(bounds) - 1)]


def forwarded_env(extra: dict[str, str] | None = None) -> dict[str, str]:
    """The environment variables workers get: ``FORWARDED_ENV`` as set here, plus ``extra``."""
    env = {k: os.environ[k] for k in FORWARDED_ENV if k in os.environ}
    env.update(extra or {})
    return env


@contextmanager
def held_interrupts() -> Iterator[None]:
    """Run the block to its end even if SIGINT comes meanwhile, then deliver that SIGINT as it would have been
    (KeyboardInterrupt under Python's default handler). Ray cancels a running task and a terminal's Ctrl-C stops
    a process this way; a write cut short (a LeRobot episode half saved) loses more than the one episode.
    Outside the main thread, where signals cannot be handled, the block simply runs."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    came: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: came.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if came:
        deliver_interrupt(previous)


def deliver_interrupt(handler: Any) -> None:
    """Do what SIGINT would have done under ``handler``: call it (Python's default raises KeyboardInterrupt),
    end the process (SIG_DFL) or nothing (SIG_IGN). The handler is called, not sent a new SIGINT: a Ray
    worker gets its cancel as a simulated SIGINT while its real one does nothing, so a re-sent signal was
    lost there and a cancelled task ran to its end (CI caught it)."""
    if callable(handler):
        handler(signal.SIGINT, None)
    elif handler == signal.SIG_DFL:
        signal.raise_signal(signal.SIGINT)
