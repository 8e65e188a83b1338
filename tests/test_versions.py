"""Caches keyed on what made them: a stage's key holds the versions of the code that made its data, a version is
bumped when its code's behaviour changes (the fingerprints below), and how a flag is spelt keys nothing."""

import json
from pathlib import Path

import pytest
from fingerprints import FINGERPRINTS, RECORDED, versions_of

from colorsort import versions
from colorsort.training import cache
from colorsort.training import pipeline_stages as stages
from colorsort.training.pipeline_stages import collect_config, command_of, part_settings
from colorsort.training.recipes import get_recipe


@pytest.mark.slow
@pytest.mark.parametrize("part", sorted(versions.VERSIONS))
def test_a_parts_behaviour_changes_only_with_its_version(part):
    recorded = json.loads(RECORDED.read_text())[part]
    assert recorded["versions"] == versions_of(part), (
        f"the {part}'s fingerprint was recorded with versions {recorded['versions']}, the code's are "
        f"{versions_of(part)}: run `python tests/fingerprints.py --write`")
    now = FINGERPRINTS[part]()
    assert now == recorded["fingerprint"], (
        f"the {part}'s behaviour changed (fingerprint {now}, recorded {recorded['fingerprint']}) and no version of "
        f"{sorted(versions_of(part))} did: bump the version of the code that changed (colorsort/versions.py), so "
        "that no cache its old behaviour made is reused, then run `python tests/fingerprints.py --write`")


def part_name(recipe_name: str = "camera-snapshot") -> str:
    config = collect_config(get_recipe(recipe_name), "default", 0, 8, 2)
    return cache.name("default-8", part_settings(config))


def test_a_cache_key_changes_with_the_experts_version_and_not_with_a_renamed_flag(monkeypatch):
    before = part_name()
    monkeypatch.setitem(versions.VERSIONS, "expert", versions.EXPERT_VERSION + 1)
    assert part_name() != before  # demos of another expert are never reused
    monkeypatch.setitem(versions.VERSIONS, "expert", versions.EXPERT_VERSION)
    assert part_name() == before

    def renamed(config):  # as if colorsort-collect's --boxes-per-episode were renamed --boxes
        return [("--boxes" if a == "--boxes-per-episode" else a) for a in command_of(config)]

    monkeypatch.setattr(stages, "command_of", renamed)
    assert part_name() == before
    assert "--boxes" in stages.command_of(collect_config(get_recipe("camera-snapshot"), "default", 0, 8, 2))


def test_workers_key_nothing_and_the_key_holds_the_code_versions():
    recipe = get_recipe("camera-snapshot")
    one, two = (part_settings(collect_config(recipe, "jitter", 2, 8, w)) for w in (1, 2))
    assert one == two and one["code"] == {"expert": versions.EXPERT_VERSION, "cell": versions.CELL_VERSION,
                                          "recorder": versions.RECORDER_VERSION}
    assert one["collect"]["episodes"] == 8 and one["collect"]["variant"] == "jitter"


def test_the_recorded_fingerprints_file_names_every_version():
    assert set(json.loads(Path(RECORDED).read_text())) == set(versions.VERSIONS)


def test_demos_recorded_under_the_shifts_training_ranges_are_keyed_on_the_shifts_version(monkeypatch):
    randomised, plain = part_name("camera-snapshot-dr"), part_name()
    monkeypatch.setitem(versions.VERSIONS, "shifts", versions.SHIFTS_VERSION + 1)
    assert part_name("camera-snapshot-dr") != randomised  # demos of other shifts are never reused
    assert part_name() == plain  # demos recorded without shifts keep their key
