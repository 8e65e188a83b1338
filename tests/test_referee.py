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
