"""Demo lights: a random-lights variant's demos recorded under lights of another brightness range.

The ``lighting`` variant draws each episode's brightness from ``LIGHT_BRIGHTNESS`` (x0.5-1.6 the cell's
light). Demos drawn from a dimmer range show a camera policy the dim end more often, where it lost the
colour of red and blue boxes (docs/baselines.md). The draws are the variant's own, so episode i's boxes and
light colour stay those of the variant's episode i; only the brightness drawn moves into the range.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

from colorsort.data.perturbations.base import LightDraw, Perturbation
from colorsort.data.perturbations.registry import register_perturbation
from colorsort.errors import ConfigError
from colorsort.variants import VARIANTS, Variant, check_brightness


@register_perturbation
@dataclass(frozen=True)
class Brightness(Perturbation):
    """A random-lights variant's brightness drawn from ``low``..``high`` [x the cell's light] instead of its own."""

    low: float
    high: float

    name = "brightness"
    metavar = "LO,HI"
    help = ("a random-lights variant's lights drawn from this brightness range [x the cell's light] instead of the "
            "variant's, e.g. 0.45,0.75 (dim)")

    def __post_init__(self) -> None:
        check_brightness("brightness", (self.low, self.high))

    @classmethod
    def parse(cls, text: str) -> Brightness:
        try:
            low, high = (float(part) for part in text.split(","))
        except ValueError as err:
            raise ConfigError(f"brightness={text!r}: give two numbers, low,high, e.g. 0.45,0.75") from err
        return cls(low, high)

    @property
    def text(self) -> str:
        return f"{self.low:g},{self.high:g}"

    def applies_to(self, variant: Variant | None, tracking: bool) -> bool:
        return variant is not None and variant.random_lights

    def refusal(self, variant: Variant | None) -> str:
        lit = [n for n, v in VARIANTS.items() if v.random_lights]
        return (f"brightness={(self.low, self.high)} sets a random-lights variant's range: give variant one of {lit} "
                f"(got {variant.name if variant else None!r})")

    @property
    def tag(self) -> str:
        return f"lit{self.low:g}-{self.high:g}"

    def settings(self) -> list[float]:
        return [self.low, self.high]

    def describe(self) -> str:
        return f"under lights of brightness x{self.low:g}-{self.high:g}"

    def lighting(self, variant: Variant) -> LightDraw:
        return partial(variant.lighting, brightness=(self.low, self.high))
