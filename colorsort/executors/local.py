"""Tasks on this machine: in this process (one worker) or one process per task, ``workers`` at once.

Processes fork from a ``forkserver`` that imported ``preload`` (seconds of torch) once and never
opened a GL context. Each reports through its own pipe, so a process killed outright cannot
wedge the others; its task runs again (``retries``). Ctrl-C goes to this process, which asks the
tasks to stop (``ctx.stopping()``) and waits for them to return what they finished.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import threading
import traceback
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.connection import wait
from typing import Any

from colorsort.executors.base import ExecutorConfig, Task, TaskResult
from colorsort.logs import quiet_robosuite_info


@dataclass
class _Context:
    send: Callable[[Any], None]
    stopping: Callable[[], bool]


def _exit_with_caller(pipe) -> None:
    """End this process as soon as the caller's end of ``pipe`` closes (the caller never sends on it):
    a caller killed outright leaves no worker writing on behind it."""
    try:
        pipe.poll(None)
    except (OSError, EOFError):
        pass
    os._exit(1)


def _entry(task: Task, pipe, stop_event) -> None:
    """A task's process: its result, or its traceback, goes back through ``pipe``."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=_exit_with_caller, args=(pipe,), daemon=True).start()
    quiet_robosuite_info()
    try:
        pipe.send(("result", task.fn(task.arg, _Context(lambda m: pipe.send(("message", m)), stop_event.is_set))))
    except BaseException:  # noqa: BLE001 - the caller reports it
        pipe.send(("error", traceback.format_exc()))
    pipe.close()


def _died(exitcode: int | None) -> str:
    if exitcode is not None and exitcode < 0:
        return f"its process was killed by {signal.Signals(-exitcode).name}"
    return f"its process exited with code {exitcode} before returning"


class LocalExecutor:
    def __init__(self, config: ExecutorConfig, preload: tuple[str, ...] = ()):
        self.config, self.preload = config, preload

    def run(self, tasks: list[Task], on_message: Callable[[Any], None] = lambda m: None,
            on_done: Callable[[TaskResult], None] = lambda r: None) -> list[TaskResult]:
        if self.config.workers == 1:
            return self._in_process(tasks, on_message, on_done)
        return self._in_processes(tasks, on_message, on_done)

    def _in_process(self, tasks, on_message, on_done) -> list[TaskResult]:
        """One task after another, here; Ctrl-C sets ``stopping`` (the task under way returns what it did)."""
        stop = []
        try:
            previous = signal.signal(signal.SIGINT, lambda *_: stop.append(True))
        except ValueError:  # not the main thread: Ctrl-C raises KeyboardInterrupt as usual
            previous = None
        results = []
        try:
            for task in tasks:
                result = TaskResult(task.key, stopped=bool(stop))
                if not stop:
                    result.attempts = 1
                    try:
                        result.value = task.fn(task.arg, _Context(on_message, lambda: bool(stop)))
                    except Exception:  # noqa: BLE001
                        result.error = traceback.format_exc()
                    on_done(result)
                results.append(result)
        finally:
            if previous is not None:
                signal.signal(signal.SIGINT, previous)
        return results

    def _in_processes(self, tasks, on_message, on_done) -> list[TaskResult]:
        ctx = mp.get_context("forkserver")
        ctx.set_forkserver_preload(list(self.preload))
        stop_event = ctx.Event()
        results = [TaskResult(t.key) for t in tasks]
        pending = deque(range(len(tasks)))
        running: dict[int, tuple[Any, Any]] = {}  # task index -> (process, pipe)
        while pending or running:
            try:
                while pending and len(running) < self.config.workers and not stop_event.is_set():
                    i = pending.popleft()
                    reader, writer = ctx.Pipe()  # duplex: the task sees this end close if the caller dies
                    process = ctx.Process(target=_entry, args=(tasks[i], writer, stop_event), daemon=False)
                    process.start()
                    writer.close()
                    running[i] = (process, reader)
                    results[i].attempts += 1
                if stop_event.is_set():
                    for i in pending:  # never started
                        results[i].stopped = True
                    pending.clear()
                wait([r for _, r in running.values()] + [p.sentinel for p, _ in running.values()], timeout=1.0)
                for i, (process, reader) in list(running.items()):
                    finished = self._drain(reader, results[i], on_message)
                    if finished or not process.is_alive():
                        process.join()
                        finished = finished or self._drain(reader, results[i], on_message)
                        del running[i]
                        reader.close()
                        if finished:
                            on_done(results[i])
                        elif results[i].attempts <= self.config.retries and not stop_event.is_set():
                            pending.appendleft(i)
                        else:
                            results[i].error = f"{tasks[i].key} failed after {results[i].attempts} attempts: " \
                                               f"{_died(process.exitcode)}"
                            on_done(results[i])
            except KeyboardInterrupt:
                stop_event.set()
        return results

    @staticmethod
    def _drain(reader, result: TaskResult, on_message) -> bool:
        """Read what a task sent; True once its result (or error) has come."""
        try:
            while reader.poll():
                kind, payload = reader.recv()
                if kind == "message":
                    on_message(payload)
                elif kind == "result":
                    result.value = payload
                    return True
                else:
                    result.error = payload
                    return True
        except (EOFError, OSError):
            pass
        return False
