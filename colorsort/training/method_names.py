"""A method's name in ColorSort's tables: the policy LeRobot trains, how the scored weights were made and DAgger's
rounds, e.g. "ACT", "ACT (mean of 2 checkpoints)", "ACT + DAgger (1 round, fine-tuned)", "Diffusion Policy"."""

from __future__ import annotations

METHODS = {"act": "ACT", "diffusion": "Diffusion Policy"}  # LeRobot's policy type -> the method's name


def method_name(policy_type: str, rounds: int = 0, retrain: str = "scratch", average: int = 1) -> str:
    """The name of the method that made a policy of LeRobot's ``policy_type``: ``average`` (checkpoints whose mean
    weights are scored; 1, one checkpoint's own), then DAgger's ``rounds`` after behaviour cloning and how each
    retrains ("scratch" or "finetune")."""
    name = METHODS[policy_type] + (f" (mean of {average} checkpoints)" if average > 1 else "")
    if not rounds:
        return name
    return f"{name} + DAgger ({rounds} round{'s' * (rounds > 1)}{', fine-tuned' * (retrain == 'finetune')})"
