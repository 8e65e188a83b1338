"""What the perturbations that hold a command back share: a number of control steps, 0 (off) to ``MAX_STEPS``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Self

from colorsort.config import check_range
from colorsort.data.perturbations.base import Perturbation
from colorsort.errors import ConfigError

MAX_STEPS = 100  # [control steps] the longest hold asked for (5 s at 20 Hz)


@dataclass(frozen=True)
class Holds(Perturbation):
    """A perturbation that holds something back 0..``max_steps`` control steps at a time; 0 is off.

    Subclasses set ``tag_prefix`` (its cache tag is ``<prefix><max_steps>``) and the protocol's class variables."""

    max_steps: int
    metavar: ClassVar[str] = "N"
    tag_prefix: ClassVar[str]

    def __post_init__(self) -> None:
        check_range(self.name, self.max_steps, 0, MAX_STEPS)

    @classmethod
    def parse(cls, text: str) -> Self:
        try:
            return cls(int(text))
        except ValueError as err:
            raise ConfigError(f"{cls.name}={text!r}: give 0 (off) to {MAX_STEPS} control steps") from err

    @property
    def text(self) -> str:
        return str(self.max_steps)

    @property
    def active(self) -> bool:
        return self.max_steps > 0

    @property
    def tag(self) -> str:
        return f"{self.tag_prefix}{self.max_steps}"

    def settings(self) -> int:
        return self.max_steps
