"""The outcome model: one judge for every layer (env, gym env, collector, replay, eval)."""

import pytest

from colorsort.cell.referee import BoxEvent, Outcome, Tally, judge

P, M, D, R = Outcome.PLACED, Outcome.MISPLACED, Outcome.DROPPED, Outcome.REJECTED


def events(*outcomes):
    bins = {P: "red", M: "green", D: None, R: None}
    return [BoxEvent(float(k), k, "yellow" if o is R else "red", o, bins[o]) for k, o in enumerate(outcomes)]


@pytest.mark.parametrize("outcomes,boxes,expected", [
    ((P, P), 2, (True, True, False, "ok")),
    ((P, R, P), 3, (True, True, False, "ok")),  # a distractor let through is handled right
    ((P,), 2, (False, False, False, "timeout")),
    ((M, P), 2, (True, False, True, "misplaced")),
    ((P, D), 2, (True, False, True, "dropped")),
    ((D,), 2, (False, False, True, "timeout")),  # failed already, not finished
    ((P, P, M), 2, (True, True, False, "ok")),  # boxes after the episode's last do not count
])
def test_judge_decides_an_episode_from_its_first_boxes(outcomes, boxes, expected):
    v = judge(events(*outcomes), boxes)
    assert (v.done, v.success, v.failed, v.reason) == expected


def test_outcomes_print_as_their_names_and_carry_the_sparse_reward():
    assert [str(o) for o in Outcome] == ["placed", "misplaced", "dropped", "rejected"]
    assert f"{R:10s}|" == "rejected  |"
    assert [o.reward for o in Outcome] == [1.0, -1.0, -1.0, 0.0]
    assert [o.handled_right for o in Outcome] == [True, False, False, True]


def test_tally_counts_each_outcome_and_judges_robosuites_success():
    tally = Tally()
    for e in events(P, P, R):
        tally.count(e)
    assert tally.placed == {"red": 2, "green": 0, "blue": 0} and tally.rejected == 1
    assert tally.success(2) and not tally.success(3) and not tally.failed
    tally.count(events(M)[0])
    assert tally.misplaced == 1 and tally.failed and not tally.success(2)


def test_one_rule_and_one_tally_for_the_cpu_cell_the_gym_env_and_the_batched_cell():
    """Random episodes' events: ``EpisodeTally`` (the rollout's results and the Gymnasium env's info), ``judge`` and the
    batched cell's array tally agree on every count, on success, and on when the episode ends (``episode_rule``)."""
    import numpy as np

    from colorsort.batched.evaluate import tally
    from colorsort.cell.referee import BoxEvent, EpisodeTally, Outcome, episode_rule, judge

    outcomes, rng, boxes = list(Outcome), np.random.default_rng(0), 3
    for _ in range(200):
        drawn = rng.integers(len(outcomes), size=int(rng.integers(0, 6)))
        events = [BoxEvent(float(t), t, "red", outcomes[o], "red" if outcomes[o] is Outcome.PLACED else None)
                  for t, o in enumerate(drawn)]
        cpu = EpisodeTally.of(events, boxes)
        padded = np.full((1, 8), -1)
        padded[0, : len(drawn)] = drawn
        warp = tally(np.array([len(drawn)]), padded, boxes)
        assert cpu.verdict == judge(events, boxes)
        assert all(cpu.counts[o] == warp[o.value][0] for o in Outcome)
        assert cpu.verdict.success == warp["success"][0] and cpu.verdict.failed == warp["failed"][0]
        _, ended = episode_rule(cpu.verdict.done, cpu.verdict.failed)
        assert ended == warp["terminated"][0] == (cpu.verdict.done or cpu.verdict.failed)
