"""The executors on their own: chunks, bad settings, a task whose process is killed runs again."""

import os
import signal

import pytest

from colorsort.executors.base import ExecutorConfig, Task, chunks
from colorsort.executors.factory import make_executor


def square(x, ctx):
    ctx.send(x)
    return x * x


def die_once(path, ctx):
    """SIGKILLs its own process the first time (``path`` remembers), returns the second."""
    if not os.path.exists(path):
        open(path, "w").close()
        os.kill(os.getpid(), signal.SIGKILL)
    return "second attempt"


def fail(x, ctx):
    raise RuntimeError("a bug in the task")


@pytest.mark.parametrize("kwargs, match", [
    (dict(name="dask"), "Valid executors: \\['local', 'ray'\\]"), (dict(workers=0), "workers"),
    (dict(retries=-1), "retries"), (dict(address="auto"), "ray executor"),
])
def test_bad_settings_name_the_valid_choices(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ExecutorConfig(**kwargs)


def test_chunks_cover_every_item_once_in_order():
    items = list(range(103))
    for size, workers in [(32, 1), (32, 8), (1, 2), (200, 3)]:
        blocks = chunks(items, size, workers)
        assert [i for b in blocks for i in b] == items
        assert max(map(len, blocks)) <= size and len(blocks) >= min(workers, len(items))
    with pytest.raises(ValueError, match="shard size"):
        chunks(items, 0)


@pytest.mark.parametrize("workers", [1, 2])
def test_local_results_come_back_in_order_with_the_messages(workers):
    messages = []
    results = make_executor(ExecutorConfig(workers=workers)).run(
        [Task(f"t{k}", square, k) for k in range(5)], messages.append)
    assert [r.value for r in results] == [0, 1, 4, 9, 16] and sorted(messages) == [0, 1, 2, 3, 4]
    assert all(r.ok and r.attempts == 1 for r in results)


def test_a_local_task_killed_outright_runs_again_and_a_raising_one_does_not(tmp_path):
    tasks = [Task("dies", die_once, str(tmp_path / "died")), Task("raises", fail, 0), Task("fine", square, 3)]
    dies, raises, fine = make_executor(ExecutorConfig(workers=2, retries=1)).run(tasks)
    assert dies.value == "second attempt" and dies.attempts == 2 and dies.ok
    assert raises.attempts == 1 and "a bug in the task" in raises.error
    assert fine.value == 9


def test_without_retries_a_killed_task_is_reported_with_its_signal(tmp_path):
    (dies,) = make_executor(ExecutorConfig(workers=2, retries=0)).run([Task("dies", die_once, str(tmp_path / "d"))])
    assert not dies.ok and "SIGKILL" in dies.error and dies.attempts == 1
