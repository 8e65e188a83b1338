"""DAgger's settings, a recipe's ``dagger`` section: how many rounds of "the policy drives, the expert labels the
states it reached, the policy is trained again" follow behaviour cloning, and how each round is played."""

from __future__ import annotations

from dataclasses import dataclass

from colorsort.errors import ConfigError

ROLLOUTS = ("last", "chosen")
RETRAINS = ("scratch", "finetune")


@dataclass(frozen=True)
class DaggerConfig:
    """DAgger (Ross et al., 2011) after behaviour cloning: rounds of "the policy drives, the expert labels the
    states it reached, the labels join the training set, the policy is trained again" (``colorsort-takeover``
    records a round's labels). Each round trains a new policy from scratch on the demos and every round's labels,
    for the recipe's updates and seeds (or, with ``retrain="finetune"``, trains the policy that played further);
    the last round's policy is the one scored. Only the largest demo set runs rounds.
    """

    # rounds after the first training; 0: behaviour cloning alone.
    rounds: int = 0
    # episodes the policy plays per round on each training variant (the expert finishes each; those it finishes with
    # every box right are kept).
    episodes: int = 10
    # [steps] (first, last): the policy acts for a number of steps drawn from this range in each episode before the
    # expert takes over.
    handover: tuple[int, int] = (20, 200)
    # which checkpoint of a round's policy plays: "last", or "chosen", the one validation seeds choose
    # (``evaluation.select_episodes``) as for scoring; a policy's checkpoints can differ by more than the methods do.
    rollout: str = "last"
    # how a round's policy is trained on the grown set: "scratch", a new policy from scratch; "finetune", the weights of
    # the checkpoint that played trained further (``lerobot-train --policy.path``; the optimizer starts afresh).
    retrain: str = "scratch"
    # [updates] each round's training; 0: as many as the first training's (the recipe's).
    updates: int = 0
    # the training variants the policy plays in each round (their labels join the set); empty: every training variant. A
    # variant keeps its takeover seeds whichever others are played.
    variants: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.rounds < 0:
            raise ConfigError(f"rounds={self.rounds}: give 0 (behaviour cloning alone) or more")
        if self.episodes < 1:
            raise ConfigError(f"episodes={self.episodes}: give at least 1")
        lo, hi = self.handover
        if not 0 <= lo <= hi:
            raise ConfigError(f"handover={self.handover}: give FIRST:LAST steps with 0 <= FIRST <= LAST")
        if self.rollout not in ROLLOUTS:
            raise ConfigError(f"rollout={self.rollout!r}: give one of {list(ROLLOUTS)}")
        if self.retrain not in RETRAINS:
            raise ConfigError(f"retrain={self.retrain!r}: give one of {list(RETRAINS)}")
        if self.updates < 0:
            raise ConfigError(f"updates={self.updates}: give 0 (as many as the first training's) or more")
