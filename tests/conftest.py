"""Shared fixtures: headless rendering, offline hub, envs that are closed whatever the test's outcome."""

import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("HF_HUB_OFFLINE", "1")
os.environ.setdefault("COLORSORT_RESULTS", "none")  # benchmark scripts a test runs write no docs/results file
# One math thread a process: the suite runs two pytest workers (and their subprocesses) on two cores, and torch's
# OpenMP and the BLAS threads of a second process only spin for a core the other holds (measured: 6% less wall)
for _threads in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_threads, "1")

import pytest  # noqa: E402
from helpers import TINY, new_env  # noqa: E402
from scale_common import QUIET, SCALE  # noqa: E402

import colorsort  # noqa: E402,F401  (registers the task)

# The modules that take longest (each one's summed test time in a full `make test`, from pytest's --junitxml; on a
# fresh machine test_batched also compiles MuJoCo Warp's kernels, minutes more), run first: each stays on one worker
# (--dist loadfile), and a long one started last kept the other worker idle for minutes at the end. The Makefile's
# --no-loadscope-reorder keeps this order (xdist's own puts the modules with the most tests first).
LONGEST_FIRST = ("test_batched", "test_scale", "test_collect", "test_lerobot_cli", "test_benchmark", "test_pipeline",
                 "test_crashes", "test_shifts", "test_takeover", "test_expert", "test_tracking", "test_clients",
                 "test_shipped", "test_demos", "test_report", "test_rollout", "test_versions")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.stem, len(rank)))  # stable: each module's own order kept


@pytest.fixture
def closing():
    """``closing(thing)`` returns ``thing`` and closes it after the test, whether the test passed or not."""
    things = []

    def register(thing):
        things.append(thing)
        return thing

    yield register
    for thing in reversed(things):
        thing.close()


@pytest.fixture
def make_env(closing):
    """``make_env(robot, **kwargs)``: ``helpers.new_env``, closed after the test."""
    return lambda robot="IRB140", **kwargs: closing(new_env(robot, **kwargs))


@pytest.fixture
def env():
    e = new_env()
    e.reset()
    yield e
    e.close()


def recorded_once(tmp_path_factory, name: str, config: dict, kept: int) -> Path:
    """A collection recorded once per run, by whichever pytest-xdist worker asks first, in the workers' common
    temporary folder (a lock file: the others wait for it). Tests read it; one that changes data works on a copy."""
    from filelock import FileLock

    from colorsort.data.collect import collect
    from colorsort.data.config import CollectConfig

    shared = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        shared = shared.parent  # pytest-of-<user>/pytest-<n>/, the workers' folders inside
    root = shared / name
    with FileLock(str(root) + ".lock"):
        if not (root / "meta" / "info.json").is_file():  # a collection publishes its folder only when complete
            summary = collect(CollectConfig(out=str(root), **config), **QUIET)
            assert summary.kept == kept and not summary.errors, summary
    return root


@pytest.fixture(scope="session")
def tiny_dataset(tmp_path_factory) -> Path:
    """Two one-box episodes of the expert, 64x64 scene and wrist cameras."""
    return recorded_once(tmp_path_factory, "tiny", TINY, kept=2)


@pytest.fixture(scope="session")
def reference(tmp_path_factory) -> Path:
    """``scale_common.SCALE``'s collection recorded in the test's process, one shard, no engine: what the scale
    and crash tests' collections must equal."""
    return recorded_once(tmp_path_factory, "scale-reference", {**SCALE, "shard_size": 32}, kept=4)
