"""The executor a configuration names: beside the engines, so that the interface (``base``) imports none of them."""

from __future__ import annotations

from colorsort.executors.base import Executor, ExecutorConfig


def make_executor(config: ExecutorConfig, preload: tuple[str, ...] = (), env: dict[str, str] | None = None) -> Executor:
    """The executor ``config`` names. ``preload``: modules local workers import once, before forking;
    ``env``: variables every worker gets (``base.forwarded_env``). Ray is imported only when asked for."""
    if config.name == "ray":
        from colorsort.executors.ray import RayExecutor

        return RayExecutor(config, env or {})
    from colorsort.executors.local import LocalExecutor

    return LocalExecutor(config, preload)
