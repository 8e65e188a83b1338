"""The protocol every demonstrator perturbation follows (DART, Laskey et al. 2017: noise in the demonstrator's
execution, so that demos show the states a learned policy reaches and what the expert does there).

A perturbation is a frozen dataclass: its fields are its settings, validated once in ``__post_init__``. It
names itself for the command line (``--<name>``), the recorded settings (``settings``) and cache folders
(``tag``), and describes itself for a shipped policy's README (``describe``). While recording it may change
an episode's lights (``lighting``) and, through the per-episode ``Hook`` that ``episode`` returns, the actions:
the recorder asks each hook in turn, innermost (lowest ``order``) first, for a ``Step`` — the action stored as
the label and the one the env executes. Adding one is one module in this package (``registry.register_perturbation``).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from colorsort.envs.rollout import Step

if TYPE_CHECKING:
    from colorsort.config import Lighting
    from colorsort.expert.base import Expert
    from colorsort.variants import Variant

LightDraw = Callable[[np.random.Generator], "Lighting"]


class Hook:
    """One episode of a perturbation: asked once per control step; by default it changes nothing."""

    def act(self, inner: Callable[[], Step]) -> Step:
        """This step's actions; ``inner()`` asks the hooks inside this one and the expert (at most once a step;
        not asking holds the expert's clock)."""
        return inner()


class Perturbation:
    """Base of the perturbations (frozen dataclasses). Subclasses set the class variables and ``parse``.

    Class variables:
        name: registry key, recorded-settings key and ``colorsort-collect`` flag (``--late-pass`` for ``late_pass``).
        metavar: the flag's value, e.g. ``N``.
        help: the flag's help, with units.
        order: where its hook sits around the expert, lowest innermost (ties: by name).
    """

    name: ClassVar[str]
    metavar: ClassVar[str]
    help: ClassVar[str]
    order: ClassVar[int] = 0

    @classmethod
    def parse(cls, text: str) -> Perturbation:
        """The perturbation a command-line value gives; ``ConfigError`` naming the valid values otherwise."""
        raise NotImplementedError

    @property
    def text(self) -> str:
        """The command-line value that ``parse`` turns back into this perturbation."""
        raise NotImplementedError

    @property
    def active(self) -> bool:
        """False where its settings change nothing (``late_pass=0``): it is then dropped from a configuration."""
        return True

    def applies_to(self, variant: Variant | None, tracking: bool) -> bool:
        """Whether it can act on demos of ``variant`` (None: a preset's task) on a belt that tracks or stops."""
        return True

    def refusal(self, variant: Variant | None) -> str:
        """Why it cannot act where ``applies_to`` is false, and what to give instead."""
        return "give it on another variant"

    @property
    def tag(self) -> str:
        """Its piece of a cache folder's name, e.g. ``late100``."""
        raise NotImplementedError

    def settings(self) -> Any:
        """What the dataset records of it (JSON), checked on ``--resume``."""
        raise NotImplementedError

    def describe(self) -> str:
        """A phrase for a shipped policy's README, e.g. "every belt pass held back 0-100 steps"."""
        raise NotImplementedError

    def lighting(self, variant: Variant) -> LightDraw | None:
        """The draw of an episode's lights on ``variant`` in its place (None: the variant's own)."""
        return None

    def episode(self, seed: int, expert: Expert) -> Hook:
        """The hook for one episode whose env seed is ``seed``, acting around ``expert``."""
        return Hook()


def perturbed(hooks: list[Hook], expert_step: Callable[[], Step]) -> Step:
    """This step's actions through ``hooks`` (innermost first) around ``expert_step``, the expert's own."""
    step = expert_step
    for hook in hooks:
        step = partial(hook.act, step)
    return step()
