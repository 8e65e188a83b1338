"""Held-out shifts: changes of the cell applied at evaluation that no recipe trains on (``docs/shifts.md``).

``SHIFTS`` maps a name to its ``Shift`` (one module each, registered on import); ``parse_shifts`` reads
``NAME:LEVEL`` texts; ``EpisodeShift`` applies a set of them to one episode of a ``ColorSort`` env, which is the
one place shifts are applied (``ColorSort(shift=...)``, ``gym.make(id, shift=...)``, ``--env.shift``,
``colorsort-eval --shift``). The policy sees only their effects.
"""

from __future__ import annotations

import importlib
import pkgutil

from colorsort.shifts.base import GROUPS, LEVELS, Shift
from colorsort.shifts.registry import ALL, SHIFTS, ShiftLevel, parse_shifts, register_shift, shift_label

for _module in pkgutil.iter_modules(__path__):
    if _module.name not in ("base", "registry", "episode", "colour"):
        importlib.import_module(f"{__name__}.{_module.name}")

__all__ = ["ALL", "GROUPS", "LEVELS", "SHIFTS", "Shift", "ShiftLevel", "parse_shifts", "register_shift", "shift_label"]
