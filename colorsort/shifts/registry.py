"""The registry of held-out shifts, and ``NAME:LEVEL`` as the command line gives it."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from colorsort.errors import ConfigError
from colorsort.shifts.base import LEVELS, Shift

SHIFTS: dict[str, Shift] = {}
ALL = "all"  # ``all:L``: every shift at level L at once


def register[T: type[Shift]](cls: T) -> T:
    """Class decorator: make ``cls`` known by its ``name``."""
    if cls.name in SHIFTS:
        raise ConfigError(f"shift {cls.name!r} is registered twice")
    SHIFTS[cls.name] = cls()
    return cls


@dataclass(frozen=True)
class ShiftLevel:
    """One shift at one level."""

    name: str
    level: int

    def __str__(self) -> str:
        return f"{self.name}:{self.level}"


def parse_one(text: str) -> list[ShiftLevel]:
    """``NAME:LEVEL`` (``all:L`` for every shift): one or, for ``all``, every shift at that level."""
    name, sep, level_text = text.strip().partition(":")
    valid = [*SHIFTS, ALL]
    if not sep or not name:
        raise ConfigError(f"shift {text!r}: give NAME:LEVEL, e.g. camera-pose:2; names: {valid}; "
                          f"levels: {list(LEVELS)}")
    if name not in valid:
        raise ConfigError(f"Unknown shift {name!r}. Valid shifts: {valid}")
    if level_text.strip() not in {str(v) for v in LEVELS}:
        raise ConfigError(f"shift {name!r}: level {level_text!r} is not one of {list(LEVELS)}")
    level = int(level_text)
    return [ShiftLevel(n, level) for n in SHIFTS] if name == ALL else [ShiftLevel(name, level)]


def parse_shifts(given: str | Iterable[str] | None) -> tuple[ShiftLevel, ...]:
    """Shifts from ``NAME:LEVEL`` texts (a list, or one comma-separated string; None or "" for none), in the
    registry's order; a shift given twice at different levels is refused. Level 0 is kept (it changes nothing)."""
    if given is None:
        return ()
    texts: Sequence[str] = [t for t in given.split(",") if t.strip()] if isinstance(given, str) else list(given)
    found: dict[str, int] = {}
    for text in texts:
        for s in parse_one(text):
            if found.get(s.name, s.level) != s.level:
                raise ConfigError(f"shift {s.name!r} given at levels {found[s.name]} and {s.level}: give one")
            found[s.name] = s.level
    return tuple(ShiftLevel(n, found[n]) for n in SHIFTS if n in found)


def shift_label(shifts: Iterable[ShiftLevel]) -> str:
    """``camera-pose:2,image-noise:1``; ``none`` for no shift (the control arm)."""
    active = [str(s) for s in shifts]
    return ",".join(active) or "none"
