"""The registry of demonstrator perturbations, and the canonical order of a set of them."""

from __future__ import annotations

from collections.abc import Iterable

from colorsort.data.perturbations.base import Perturbation
from colorsort.errors import ConfigError

PERTURBATIONS: dict[str, type[Perturbation]] = {}


def register[T: type[Perturbation]](cls: T) -> T:
    """Class decorator: make ``cls`` known by its ``name``."""
    if cls.name in PERTURBATIONS:
        raise ConfigError(f"perturbation {cls.name!r} is registered twice")
    PERTURBATIONS[cls.name] = cls
    return cls


def parse(name: str, text: str) -> Perturbation:
    """The perturbation ``name`` with the command-line value ``text``."""
    if name not in PERTURBATIONS:
        raise ConfigError(f"Unknown perturbation {name!r}. Valid perturbations: {sorted(PERTURBATIONS)}")
    return PERTURBATIONS[name].parse(text)


def canonical(perturbations: Iterable[Perturbation]) -> tuple[Perturbation, ...]:
    """The active ones, one per name, in the order of their names (the order their tags join in)."""
    found: dict[str, Perturbation] = {}
    for p in perturbations:
        if not isinstance(p, Perturbation) or p.name not in PERTURBATIONS:
            raise ConfigError(f"{p!r} is not a registered perturbation; valid: {sorted(PERTURBATIONS)}")
        if p.name in found:
            raise ConfigError(f"perturbation {p.name!r} given twice: {found[p.name]!r} and {p!r}")
        found[p.name] = p
    return tuple(sorted((p for p in found.values() if p.active), key=lambda p: p.name))
