"""The registry of held-out shifts, and ``NAME:LEVEL`` as the command line gives it (``LEVEL`` 0-3, or ``train``
for a trainable shift's training range)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from colorsort.errors import ConfigError, UnknownName
from colorsort.shifts.base import LEVELS, TRAIN, Shift

SHIFTS: dict[str, Shift] = {}
ALL = "all"  # ``all:L``: every shift at level L at once


def register_shift[T: type[Shift]](cls: T) -> T:
    """Class decorator: make ``cls`` known by its ``name``."""
    if cls.name in SHIFTS:
        raise ConfigError(f"shift {cls.name!r} is registered twice")
    SHIFTS[cls.name] = cls()
    return cls


@dataclass(frozen=True)
class ShiftLevel:
    """One shift at one level: 0-3, or ``TRAIN`` (a value in its training range, drawn per episode)."""

    name: str
    level: int | str

    @property
    def active(self) -> bool:
        """Whether it changes anything (level 0 does not)."""
        return self.level != 0

    @property
    def held_out(self) -> bool:
        """Whether it sets a held-out level (1-3), which no recipe may train on."""
        return self.level != 0 and self.level != TRAIN

    def __str__(self) -> str:
        return f"{self.name}:{self.level}"


def trainable() -> list[str]:
    """The shifts with a training range, in the registry's order."""
    return [n for n, s in SHIFTS.items() if s.trainable]


def parse_one(text: str) -> list[ShiftLevel]:
    """``NAME:LEVEL`` (``all:L`` for every shift, ``all:train`` for every trainable one): one shift or several."""
    name, sep, level_text = text.strip().partition(":")
    valid, level_text = [*SHIFTS, ALL], level_text.strip()
    if not sep or not name:
        raise ConfigError(f"shift {text!r}: give NAME:LEVEL, e.g. camera-pose:2; names: {valid}; "
                          f"levels: {[*LEVELS, TRAIN]}")
    if name not in valid:
        raise UnknownName("shift", name, valid, "shifts")
    if level_text == TRAIN:
        if name == ALL:
            return [ShiftLevel(n, TRAIN) for n in trainable()]
        if not SHIFTS[name].trainable:
            raise ConfigError(f"shift {name!r} has no training range; shifts that have one: {trainable()}")
        return [ShiftLevel(name, TRAIN)]
    if level_text not in {str(v) for v in LEVELS}:
        raise ConfigError(f"shift {name!r}: level {level_text!r} is not one of {[*LEVELS, TRAIN]}")
    level = int(level_text)
    return [ShiftLevel(n, level) for n in SHIFTS] if name == ALL else [ShiftLevel(name, level)]


def parse_shifts(given: str | Iterable[str] | None) -> tuple[ShiftLevel, ...]:
    """Shifts from ``NAME:LEVEL`` texts (a list, or one comma-separated string; None or "" for none), in the
    registry's order; a shift given twice at different levels is refused. Level 0 is kept (it changes nothing)."""
    if given is None:
        return ()
    if not isinstance(given, str) and not (isinstance(given, Iterable) and all(isinstance(t, str) for t in given)):
        raise ConfigError(f"shift={given!r}: give NAME:LEVEL texts, a list or one comma-separated string "
                          f"(e.g. 'camera-pose:2'); names: {[*SHIFTS, ALL]}; levels: {[*LEVELS, TRAIN]}")
    texts: Sequence[str] = [t for t in given.split(",") if t.strip()] if isinstance(given, str) else list(given)
    found: dict[str, int | str] = {}
    for text in texts:
        for s in parse_one(text):
            if found.get(s.name, s.level) != s.level:
                raise ConfigError(f"shift {s.name!r} given at levels {found[s.name]} and {s.level}: give one")
            found[s.name] = s.level
    return tuple(ShiftLevel(n, found[n]) for n in SHIFTS if n in found)


def training_shifts(given: str | Iterable[str] | None, what: str) -> tuple[ShiftLevel, ...]:
    """Shifts that data to train on may be recorded with: training ranges (``NAME:train``) and level 0 only. A
    held-out level is refused, naming it and its values: no recipe randomises into what the shifts hold out."""
    shifts = parse_shifts(given)
    for s in shifts:
        if s.held_out:
            shift = SHIFTS[s.name]
            hint = (f"train on {s.name}:train (up to {shift.level_text(1)}, exclusive)" if shift.trainable else
                    f"{s.name!r} has no training range; shifts that have one: {trainable()}")
            raise ConfigError(f"{what}: {s} randomises into held-out level {s.level} of {s.name!r} "
                              f"({shift.level_text(int(s.level))}): levels 1-3 are for evaluation only; {hint}")
    return shifts


def shift_label(shifts: Iterable[ShiftLevel]) -> str:
    """``camera-pose:2,image-noise:1``; ``none`` for no shift (the control arm)."""
    active = [str(s) for s in shifts]
    return ",".join(active) or "none"
