"""Quiet start-up: robosuite's import-time notices that say nothing about ColorSort.

``import robosuite`` logs five warnings on every start: no private macro file (ColorSort sets
the macros it needs in code), no ``robosuite_models`` package and no mink whole-body IK (robots
and a controller ColorSort does not use). ``quiet_robosuite_startup`` drops exactly those
records from robosuite's logger; any other robosuite warning still shows.
"""

from __future__ import annotations

import logging

ROBOSUITE_LOGGER = "robosuite_logs"
STARTUP_NOTICES = (
    "No private macro file found",
    "It is recommended to use a private macro file",
    "To setup, run:",
    "Could not import robosuite_models",
    "Could not load the mink-based whole-body IK",
)


class _DropStartupNotices(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return not str(record.msg).startswith(STARTUP_NOTICES)


def quiet_robosuite_startup() -> None:
    """Drop robosuite's start-up notices (call before robosuite is imported; idempotent)."""
    logger = logging.getLogger(ROBOSUITE_LOGGER)
    if not any(isinstance(f, _DropStartupNotices) for f in logger.filters):
        logger.addFilter(_DropStartupNotices())


def quiet_robosuite_info() -> None:
    """Show only robosuite's warnings and errors (its INFO lines name every controller file it loads)."""
    logging.getLogger(ROBOSUITE_LOGGER).setLevel(logging.WARNING)
