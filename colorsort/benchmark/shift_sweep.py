"""A policy's whole held-out sweep: the control arm and every shift at every level, on the same seeds.

Every arm runs on ``SHIFT_SEEDS`` (episode k on the k-th), so arm and control differ only by the shift. The arms'
episodes are dealt into one job per worker; a job builds one env (or ``batch_size`` cells) and one policy and
switches the env's shifts between arms (``ColorSortGymEnv.set_shift``), so a sweep of 49 arms builds two envs on
two workers, not 49.
Relative success (shifted / control) has a conservative 95% interval: the arm's Wilson bounds over the control's
(low / high, high / low), which stays honest where both rates sit at 100% (a ratio's usual log interval collapses
to a point there).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

from colorsort.benchmark.episode_result import EpisodeResult
from colorsort.benchmark.evaluate import EvalConfig, Finished, run_episodes
from colorsort.benchmark.lockstep import EpisodePlan
from colorsort.benchmark.metrics import EvalReport, aggregate
from colorsort.benchmark.policies import check_policy_spec
from colorsort.benchmark.sweep_journal import Key
from colorsort.cell.cameras import DEFAULT_CAMERAS, DEFAULT_IMAGE_SIZE
from colorsort.errors import ConfigError, Interrupted
from colorsort.executors.base import DEFAULT_SHARD_SIZE, ExecutorConfig
from colorsort.shifts import ALL, LEVELS, SHIFTS, parse_shifts, shift_label
from colorsort.variants import SHIFT_SEEDS, get_variant

CONTROL = "none"


@dataclass(frozen=True)
class Arm:
    """One arm of a sweep: a shift at a level (``none`` for the control) and its number of episodes."""

    shift: str
    episodes: int

    @property
    def name(self) -> str:
        return self.shift.partition(":")[0]

    @property
    def level(self) -> int:
        return int(self.shift.partition(":")[2] or 0)

    @property
    def keys(self) -> list[Key]:
        """Its episodes as a journal keys them: (its shift, seed) on the first ``episodes`` shift seeds."""
        return [(self.shift, seed) for seed in SHIFT_SEEDS[: self.episodes]]


def sweep_arms(episodes: int, side_episodes: int, levels: tuple[int, ...] = (1, 2, 3),
               names: tuple[str, ...] | None = None) -> list[Arm]:
    """The control (``episodes``), then each shift at each of ``levels``: ``episodes`` at level 2, ``side_episodes``
    at the others. ValueError for an unknown shift or level, or more episodes than ``SHIFT_SEEDS``."""
    if names and ALL in names:
        names = None  # every shift, as --list-shifts offers it
    for given in names or ():
        if ":" in given:
            raise ConfigError(f"--sweep-shifts {given}: give shift names alone (--levels picks the levels), e.g. "
                              f"{given.partition(':')[0]}; names: {[*SHIFTS, ALL]}")
    for lv in levels:
        parse_shifts([f"{n}:{lv}" for n in names or ()])  # ValueError naming the valid shifts and levels
    names = tuple(n for n in SHIFTS if names is None or n in names)  # in the registry's order
    if 0 in levels:
        raise ConfigError(f"levels {levels}: level 0 is the control arm, which a sweep always runs; give some of "
                          f"{list(LEVELS[1:])}")
    for n in (episodes, side_episodes):
        if not 1 <= n <= len(SHIFT_SEEDS):
            raise ConfigError(f"{n} episodes an arm: give 1 to {len(SHIFT_SEEDS)} (the shift evaluation seeds)")
    return [Arm(CONTROL, episodes)] + [Arm(f"{n}:{lv}", episodes if lv == 2 else side_episodes)
                                       for n in names for lv in levels]


def run_sweep(policy: str, variant: str, arms: list[Arm], *, image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE,
              cameras: tuple[str, ...] = DEFAULT_CAMERAS, episode_length: int | None = None,
              executor: ExecutorConfig = ExecutorConfig(), shard_size: int = DEFAULT_SHARD_SIZE,
              progress: bool = True, done: Mapping[Key, EpisodeResult] | None = None,
              on_episode: Callable[[str, EpisodeResult], None] | None = None, batch_size: int = 1,
              precision: str = "float32") -> list[EvalReport]:
    """Every arm's report, in order (the control's ``shift`` is ``none``); the same whatever the executor, its
    workers, ``shard_size`` (episodes a job, at most) and ``batch_size`` (cells a job steps together). Episodes in
    ``done`` (by arm shift and seed: a ``SweepJournal``'s) are not run again; ``on_episode(arm shift, result)`` is
    called as each new one finishes.

    Raises:
        Interrupted: the sweep was stopped (Ctrl-C); the episodes that finished went to ``on_episode``.
    """
    check_policy_spec(policy)
    get_variant(variant)
    done = done or {}
    path = policy if policy in ("expert", "random") else str(Path(policy).resolve())
    settings = EvalConfig(path, variant, image_size, tuple(cameras), episode_length, batch_size=batch_size,
                          precision=precision)
    episodes = [EpisodePlan(seed, () if shift == CONTROL else (shift,))
                for arm in arms for shift, seed in arm.keys if (shift, seed) not in done]

    def finished(message: Finished) -> None:
        if on_episode is not None:
            on_episode(arm_shift(message[1]), message[2])

    found = {**done, **{(arm_shift(shift), r.seed): r for _, shift, r in
                        run_episodes([(settings, episodes)], executor, shard_size, progress,
                                     f"{policy} on {variant}: {len(arms)} arms", finished)}}
    wanted = [key for a in arms for key in a.keys]
    if any(key not in found for key in wanted):
        raise Interrupted(sum(key in found for key in wanted), len(wanted))
    return [aggregate(policy, variant, [found[key] for key in a.keys],
                      shift_label(parse_shifts(() if a.shift == CONTROL else (a.shift,))))
            for a in arms]


def arm_shift(shift: tuple[str, ...]) -> str:
    """An episode's arm as the journal names it: its shift, or ``none`` for the control."""
    return shift[0] if shift else CONTROL


def relative(report: EvalReport, control: EvalReport) -> tuple[float | None, tuple[float, float] | None]:
    """Success relative to the control (shifted / control) and its conservative 95% interval (the module's
    docstring); None if the control sorted nothing."""
    if control.successes == 0:
        return None, None
    (lo, hi), (c_lo, c_hi) = report.success_ci95, control.success_ci95
    return report.success_rate / control.success_rate, (lo / c_hi, hi / c_lo)


def stalled(report: EvalReport) -> int:
    """Episodes that ran to the time limit."""
    return sum(e["ended"] == "time limit" for e in report.per_episode)


def sweep_rows(reports: list[EvalReport]) -> list[dict]:
    """One row per arm: shift, level, episodes, success and its interval, relative success and its interval,
    boxes misplaced and dropped, episodes stalled (the JSON's ``rows`` and the printed table)."""
    control = next(r for r in reports if r.shift == CONTROL)
    rows = []
    for r in reports:
        rel, rel_ci = relative(r, control)
        name, _, level = r.shift.partition(":")
        rows.append({"shift": name, "level": int(level or 0), "episodes": r.episodes,
                     "success": r.success_rate, "success_ci95": list(r.success_ci95),
                     "relative": rel, "relative_ci95": list(rel_ci) if rel_ci else None,
                     "misplaced": r.misplaced, "dropped": r.dropped, "stalled": stalled(r)})
    return rows


def format_sweep(policy: str, variant: str, rows: list[dict]) -> str:
    """The sweep as a table, the control first."""
    lines = [f"policy {policy} on {variant}, shift evaluation seeds {SHIFT_SEEDS[0]}.. (every arm the same seeds)",
             f"{'shift':<18} {'level':>5} {'episodes':>8} {'success':>8} {'95% CI':>13} {'relative':>8} "
             f"{'95% CI':>13} {'misplaced':>9} {'dropped':>7} {'stalled':>7}"]
    for row in rows:
        lo, hi = row["success_ci95"]
        rel = f"{100 * row['relative']:.0f}%" if row["relative"] is not None else "-"
        rci = (f"{100 * row['relative_ci95'][0]:.0f}-{100 * row['relative_ci95'][1]:.0f}%"
               if row["relative_ci95"] else "-")
        ci = f"{100 * lo:.0f}-{100 * hi:.0f}%"
        lines.append(f"{row['shift']:<18} {row['level']:>5} {row['episodes']:>8} {100 * row['success']:>7.0f}% "
                     f"{ci:>13} {rel:>8} {rci:>13} {row['misplaced']:>9} {row['dropped']:>7} {row['stalled']:>7}")
    return "\n".join(lines)
