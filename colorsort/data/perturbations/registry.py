"""The registry of demonstrator perturbations, and the canonical order of a set of them."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import draccus

from colorsort.data.perturbations.base import Perturbation
from colorsort.errors import ConfigError, UnknownName

PERTURBATIONS: dict[str, type[Perturbation]] = {}


def register_perturbation[T: type[Perturbation]](cls: T) -> T:
    """Class decorator: make ``cls`` known by its ``name``."""
    if cls.name in PERTURBATIONS:
        raise ConfigError(f"perturbation {cls.name!r} is registered twice")
    PERTURBATIONS[cls.name] = cls
    draccus.encode.register(cls, as_text)  # draccus dispatches its encoders on the exact class
    return cls


def parse(name: str, text: str) -> Perturbation:
    """The perturbation ``name`` with the command-line value ``text``."""
    if name not in PERTURBATIONS:
        raise UnknownName("perturbation", name, sorted(PERTURBATIONS), "perturbations")
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


def as_text(p: Perturbation, declared_type: object = None) -> str:
    """A perturbation as a configuration file or a list flag writes it: ``NAME:VALUE`` (``late_pass:100``)."""
    return f"{p.name}:{p.text}"


def from_text(text: str) -> Perturbation:
    """``as_text``'s inverse; ConfigError naming the valid perturbations or values otherwise."""
    name, colon, value = str(text).partition(":")
    if not colon:
        raise ConfigError(f"perturbation {text!r}: give NAME:VALUE with NAME one of {sorted(PERTURBATIONS)}")
    return parse(name, value)



@draccus.decode.register(Perturbation)  # the commands' configurations hold perturbations as NAME:VALUE
def _decode(raw: object, path: Sequence[str] = ()) -> Perturbation:
    return from_text(str(raw))
