"""The errors ColorSort raises on purpose, and the exit status each gives a console script.

Every one is a subclass of the built-in exception a caller would already catch (``ValueError`` for a bad
value, ``FileExistsError`` for data that would be overwritten, ``RuntimeError`` for a failed job), so
``except ValueError`` keeps working; ``except ColorSortError`` catches them all. ``exit_code`` is the one
place that maps them to exit codes, for every CLI (``colorsort.cli.run.guarded``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np


class ColorSortError(Exception):
    """Base of every error ColorSort raises on purpose."""


class ConfigError(ColorSortError, ValueError):
    """An invalid setting, argument or name; the message names the valid choices."""


class UnknownName(ConfigError):
    """A name looked up that is not there; the message and ``valid`` list every name that is, as mink's
    ``InvalidFrame`` does.

    Args:
        kind: what was looked up ("shift", "colour(s)").
        name: what was asked for: a name, or a list of them.
        valid: every valid name, in the order to show them.
        plural: ``kind`` in the plural, before the list (default: ``kind`` + "s").
    """

    def __init__(self, kind: str, name: object, valid: Iterable[object], plural: str | None = None):
        self.kind, self.name, self.valid = kind, name, list(valid)
        super().__init__(f"Unknown {kind} {name!r}. Valid {plural or kind + 's'}: {self.valid}")


class ActionError(ColorSortError, ValueError):
    """An action the env cannot take: wrong shape or not finite."""


def checked_action(action: object, dim: int, names: Callable[[], list[str]]) -> np.ndarray:
    """``action`` as a float64 vector of ``dim`` finite elements; ``ActionError`` naming the bad ones otherwise
    (``names()``: one name per element)."""
    action = np.asarray(action, dtype=float)
    if action.shape != (dim,):
        raise ActionError(f"Expected an action of shape ({dim},), got {action.shape}")
    bad = np.flatnonzero(~np.isfinite(action))
    if bad.size:
        raise ActionError("Action elements must be finite; got "
                          + ", ".join(f"{names()[i]} (index {i}) = {action[i]}" for i in bad))
    return action


class DataConflictError(ColorSortError, ValueError):
    """Data on disk was made with other settings than the ones asked for (a resume, a reused stage);
    nothing was changed."""


class DataExistsError(ColorSortError, FileExistsError):
    """The output exists and would be overwritten; nothing was changed."""


class StageError(ColorSortError, RuntimeError):
    """A stage, job or worker failed (its command and the end of its output are in the message)."""


class Interrupted(ColorSortError, KeyboardInterrupt):
    """A run stopped by Ctrl-C after ``finished`` of its ``total`` episodes (or items); what finished was kept."""

    def __init__(self, finished: int, total: int, kept: str | None = None):
        """``kept``: where what finished is (the message's end; default: how many finished)."""
        super().__init__(f"interrupted: {kept or f'{finished} of {total} episodes finished'}")
        self.finished, self.total = finished, total


class PlanningError(ColorSortError, RuntimeError):
    """The expert could not plan a motion or a box (ruckig, the box pool)."""


USAGE = 2  # bad arguments, or data that would be overwritten or mixed
FAILED = 1  # the work ran and failed
INTERRUPTED = 130  # Ctrl-C (128 + SIGINT), as a shell reports it

# the first entry an error is an instance of gives its exit status
EXIT_CODES: tuple[tuple[type[BaseException], int], ...] = (
    (KeyboardInterrupt, INTERRUPTED),
    (ValueError, USAGE),  # ConfigError, ActionError, DataConflictError, and a bad number parsed from a flag
    (FileExistsError, USAGE),  # DataExistsError
    (ColorSortError, FAILED),
    (RuntimeError, FAILED),
)


def exit_code(err: BaseException) -> int:
    """The exit status a console script ends with on ``err``."""
    return next((code for kind, code in EXIT_CODES if isinstance(err, kind)), FAILED)
