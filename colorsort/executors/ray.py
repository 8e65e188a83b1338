"""Tasks on a Ray cluster: ``ray.init()`` starts one on this machine, or joins ``address`` ("auto" for
the cluster this node belongs to, as on a SLURM allocation that ran ``ray start``).

Each task takes 1 CPU; Ray runs a task again when its worker process or node dies (``max_retries``),
never on an exception of the task itself. Tasks report through a ``ray.util.queue.Queue``, each message
tagged with its run (the queue is an actor, a worker process of its own: one per driver and cluster,
kept for the driver's later runs); a "start" message per attempt is how retries are counted. Ctrl-C
cancels the tasks: a running one gets KeyboardInterrupt and returns what it finished; one that has not
returned ``cancel_wait_s`` after its cancel is killed (``force``) and reported stopped, never ok.
Workers must have colorsort installed, at the same version, and see the same file system for the paths
they are given.
"""

from __future__ import annotations

import logging
import time
import uuid
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from colorsort.executors.base import ExecutorConfig, Task, TaskResult


@dataclass
class _Context:
    queue: Any
    run: str
    key: str

    def send(self, message: Any) -> None:
        self.queue.put((self.run, "message", self.key, message))

    def stopping(self) -> bool:
        return False  # Ray cancels a task by raising KeyboardInterrupt in it


def _entry(task: Task, queue, run: str) -> Any:
    from colorsort.logs import quiet_robosuite_info

    quiet_robosuite_info()
    queue.put((run, "start", task.key, None))
    return task.fn(task.arg, _Context(queue, run, task.key))


_queue: tuple[tuple[str, str], Any] | None = None  # ((this driver's node, new with each cluster; its job), queue)


def message_queue() -> Any:
    """This driver's message queue on the cluster it is connected to, made on first use; a queue whose actor is
    gone is made again."""
    global _queue
    import ray
    from ray.util.queue import Queue

    context = ray.get_runtime_context()
    key = (context.get_node_id(), context.get_job_id())
    if _queue is not None and _queue[0] == key:
        try:
            _queue[1].qsize()
            return _queue[1]
        except ray.exceptions.RayError:
            pass
    _queue = (key, Queue())
    return _queue[1]


class RayExecutor:
    """Runs tasks as Ray tasks of 1 CPU each.

    Args:
        config: the engine's settings (workers, retries, the cluster's address).
        env: environment variables every worker gets.
        cancel_wait_s: [s] how long a cancelled task may take to return what it finished before it is killed.
            On a loaded 2-core machine a cancel took 40 s to reach a task.
    """

    def __init__(self, config: ExecutorConfig, env: dict[str, str], cancel_wait_s: float = 120.0):
        self.config, self.env, self.cancel_wait_s = config, env, cancel_wait_s

    def run(self, tasks: list[Task], on_message: Callable[[Any], None] = lambda m: None,
            on_done: Callable[[TaskResult], None] = lambda r: None) -> list[TaskResult]:
        import ray

        started_here = not ray.is_initialized()
        if started_here:
            # "local": a new cluster here, never one that an earlier `ray start` on this machine left behind
            ray.init(address=self.config.address or "local", runtime_env={"env_vars": self.env},
                     include_dashboard=False, logging_level=logging.WARNING)
        batch = _Batch(tasks, message_queue(), on_message, on_done)
        remote = ray.remote(_entry).options(num_cpus=1, max_retries=self.config.retries, retry_exceptions=False)
        try:
            while batch.pending or batch.running:
                while batch.pending and len(batch.running) < self.config.workers:
                    i = batch.pending.popleft()
                    batch.running[remote.remote(tasks[i], batch.queue, batch.run)] = i
                done, _ = ray.wait(list(batch.running), num_returns=len(batch.running), timeout=0.5)
                batch.drain()
                for ref in done:
                    batch.finish(ref)
        except KeyboardInterrupt:
            batch.stop(self.cancel_wait_s)
        finally:
            batch.drain()
            if started_here:
                batch.queue.shutdown()
                ray.shutdown()
        return batch.results


class _Batch:
    """The tasks of one ``RayExecutor.run``: those waiting, those running (by their object refs), their results, and the
    queue their messages come back on (tagged with this run's id: a task of an earlier run, stopped since, is not
    this run's)."""

    def __init__(self, tasks: list[Task], queue: Any, on_message: Callable[[Any], None],
                 on_done: Callable[[TaskResult], None]):
        self.tasks, self.queue, self.on_message, self.on_done = tasks, queue, on_message, on_done
        self.run = uuid.uuid4().hex
        self.results = [TaskResult(t.key) for t in tasks]
        self.index = {t.key: i for i, t in enumerate(tasks)}
        self.pending: deque[int] = deque(range(len(tasks)))
        self.running: dict = {}

    def drain(self) -> None:
        """Hand on the messages that came back: starts count attempts, the rest go to ``on_message``."""
        for sender, kind, key, payload in self.queue.get_nowait_batch(self.queue.qsize()):
            if sender != self.run:
                continue
            if kind == "start":
                self.results[self.index[key]].attempts += 1
            else:
                self.on_message(payload)

    def finish(self, ref: Any) -> None:
        """A task's object ``ref`` is ready: its value, or why it has none."""
        import ray

        i = self.running.pop(ref)
        try:
            self.results[i].value = ray.get(ref)
        except ray.exceptions.TaskCancelledError:
            self.results[i].stopped = True
        except ray.exceptions.RayError as err:
            self.results[i].error = f"{self.tasks[i].key}: {err}"
        self.on_done(self.results[i])

    def stop(self, wait_s: float) -> None:
        """Ctrl-C: nothing more starts; each running task is cancelled and given ``wait_s`` [s] to return what it
        finished, then killed and reported stopped."""
        import ray

        for i in self.pending:
            self.results[i].stopped = True
        for ref in self.running:
            ray.cancel(ref)
        deadline = time.monotonic() + wait_s  # a cancelled task finalizes what it recorded
        while self.running and time.monotonic() < deadline:
            done, _ = ray.wait(list(self.running), num_returns=len(self.running), timeout=1.0)
            for ref in done:
                self.finish(ref)
        for ref, i in list(self.running.items()):  # never reached by its cancel: stopped, whatever it was doing
            ray.cancel(ref, force=True)
            self.running.pop(ref)
            self.results[i].stopped = True
            self.results[i].error = f"{self.tasks[i].key}: still running {wait_s:g} s after its cancel; killed"
            self.on_done(self.results[i])
