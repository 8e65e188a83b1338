"""How an ACT checkpoint executes its action chunks, as a copy of the checkpoint that says so.

``chunkN`` executes the first N of each chunk open-loop (LeRobot's default is 10 of 20); ``ensC`` predicts every
step and executes the average of every chunk's prediction for that step, weights exp(-C * age) (ACT's temporal
ensembling). Neither changes the trained weights, so an execution is the same checkpoint with its ``config.json``
rewritten (``with_execution``); ``benchmarks/bench_execution.py`` scores several side by side.
"""

from __future__ import annotations

import json
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from colorsort.benchmark import evaluate as evaluation
from colorsort.errors import ConfigError
from colorsort.variants import VALIDATION_SEEDS, get_variant


def inference_settings(execution: str) -> dict[str, float | int | None]:
    """``chunk10`` -> 10 actions open-loop; ``ens0.01`` -> temporal ensembling with coefficient 0.01."""
    if execution.startswith("chunk"):
        return {"n_action_steps": int(execution.removeprefix("chunk")), "temporal_ensemble_coeff": None}
    if execution.startswith("ens"):
        return {"n_action_steps": 1, "temporal_ensemble_coeff": float(execution.removeprefix("ens"))}
    raise ConfigError(f"execution {execution!r}: give chunkN (e.g. chunk10) or ensC (e.g. ens0.01)")


def with_execution(policy: Path, execution: str, folder: Path) -> Path:
    """A copy of checkpoint ``policy`` under ``folder`` whose config.json executes as ``execution`` says."""
    copy = folder / execution
    shutil.copytree(policy, copy)
    config = json.loads((copy / "config.json").read_text())
    (copy / "config.json").write_text(json.dumps({**config, **inference_settings(execution)}, indent=4))
    return copy


def execution_table(policy: str, variants: list[str], executions: list[str], episodes: int, envs: int = 2,
                    validation: bool = False) -> Iterator[str]:
    """The Markdown lines of ``policy`` scored under each execution on each variant's first ``episodes`` evaluation
    seeds (``validation``: the validation seeds instead, which no evaluation scores). Every name is checked before
    any episode runs."""
    for execution in executions:
        inference_settings(execution)
    for variant in variants:
        get_variant(variant)
    cameras, size = evaluation.observation_settings(policy, None, None)
    seeds = "validation seeds" if validation else "evaluation seeds of each"
    yield f"{policy} on {', '.join(repr(v) for v in variants)}, first {episodes} {seeds}"
    yield "| variant | execution | success rate (95% CI) | correct | misplaced | dropped | distractors let through |"
    yield "| --- | --- | --- | --- | --- | --- | --- |"
    with tempfile.TemporaryDirectory() as tmp:
        policies = {e: with_execution(Path(policy), e, Path(tmp)) for e in executions}
        for variant in variants:
            for execution, copy in policies.items():
                r = evaluation.evaluate(str(copy), variant, episodes, image_size=size, cameras=cameras, progress=False,
                                        envs=envs, seed=VALIDATION_SEEDS[0] if validation else None)
                lo, hi = r.success_ci95
                yield (f"| {variant} | {execution} | {100 * r.success_rate:.0f}% ({100 * lo:.0f}-{100 * hi:.0f}%) "
                       f"| {r.correct} | {r.misplaced} | {r.dropped} | {r.distractors_let_through}/{r.distractors} |")
