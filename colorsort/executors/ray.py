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
        queue, run = message_queue(), uuid.uuid4().hex
        remote = ray.remote(_entry).options(num_cpus=1, max_retries=self.config.retries, retry_exceptions=False)
        results = [TaskResult(t.key) for t in tasks]
        index = {t.key: i for i, t in enumerate(tasks)}
        pending: deque[int] = deque(range(len(tasks)))
        running: dict = {}

        def drain() -> None:
            for sender, kind, key, payload in queue.get_nowait_batch(queue.qsize()):
                if sender != run:  # a task of an earlier run, stopped since
                    continue
                if kind == "start":
                    results[index[key]].attempts += 1
                else:
                    on_message(payload)

        def finish(ref) -> None:
            i = running.pop(ref)
            try:
                results[i].value = ray.get(ref)
            except ray.exceptions.TaskCancelledError:
                results[i].stopped = True
            except ray.exceptions.RayError as err:
                results[i].error = f"{tasks[i].key}: {err}"
            on_done(results[i])

        try:
            while pending or running:
                while pending and len(running) < self.config.workers:
                    i = pending.popleft()
                    running[remote.remote(tasks[i], queue, run)] = i
                done, _ = ray.wait(list(running), num_returns=len(running), timeout=0.5)
                drain()
                for ref in done:
                    finish(ref)
        except KeyboardInterrupt:
            for i in pending:
                results[i].stopped = True
            for ref in running:
                ray.cancel(ref)
            deadline = time.monotonic() + self.cancel_wait_s  # a cancelled task finalizes what it recorded
            while running and time.monotonic() < deadline:
                done, _ = ray.wait(list(running), num_returns=len(running), timeout=1.0)
                for ref in done:
                    finish(ref)
            for ref, i in list(running.items()):  # never reached by its cancel: stopped, whatever it was doing
                ray.cancel(ref, force=True)
                running.pop(ref)
                results[i].stopped = True
                results[i].error = f"{tasks[i].key}: still running {self.cancel_wait_s:g} s after its cancel; killed"
                on_done(results[i])
        finally:
            drain()
            if started_here:
                queue.shutdown()
                ray.shutdown()
        return results
