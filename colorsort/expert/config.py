"""The scripted expert's settings: heights, offsets, tolerances and timings, in one frozen dataclass."""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import Any

from colorsort.config import check_range
from colorsort.errors import ConfigError
from colorsort.expert.perception import PerceptionConfig
from colorsort.expert.planning import MotionConfig


@dataclass(frozen=True)
class ExpertConfig:
    """Settings of the scripted expert. Heights and offsets come from the cell's geometry (``CellLayout``).

    Attributes:
        motion: joint speed, acceleration and jerk limits.
        perception: the colour sensor's thresholds.
        carry_z: [m] cup height while carrying: the box bottom clears the belt rails by 8 cm.
        touch_clearance: [m] the touch-off (``touch.py``) starts this far over the tallest box the cell accepts.
        touch_speed: [m/s] the touch-off's guarded descent: the reference runs on at most this times the control
            period past the touch before it stops.
        touch_floor: [m] the touch-off gives up this far under the top of the lowest box the cell accepts.
        press: [m] on a tracking belt, the cup goes on down this far past the seal before it holds and lifts (a
            deliberate dip; 0: it lifts from where the seal formed).
        drop_clearance: [m] box bottom above a bin's rim at release.
        wait_offset_y: [m] the wait pose lies this far from the belt centre, toward the bins (out of view).
        drop_slots: release points per bin, used in turn so that boxes do not pile up.
        drop_spread: the fraction of a bin's floor (clear of its walls) the candidate release points span,
            about its centre: 1 spreads them to 1 cm from the walls, lower draws them in, so that the quickest
            slots lie nearer the centre (a policy that lets go a little short or long still hits the bin).
        wait_tolerance: [rad] max joint error that counts as arrived at the wait pose.
        approach_tolerance: [rad] the same over the box and on it (the cup must sit flat).
        lift_tolerance: [rad] the same at the top of the lift.
        drop_tolerance: [rad] the same over a bin.
        release_time: [s] time after the seal is gone before moving on (the box falls clear).
        sensor_image_size: [px] side of the photo the expert takes when the ray fires (its own, whatever
            cameras the env renders).
        track_hold_time: [s] on a tracking belt, on the box after the seal (and the ``press``) before the lift.
        track_lift_time: [s] then up until the box's bottom is ``track_lift_gap`` over the belt, still moving
            with it; the carry to its bin leaves on the way (``track_carry_at``).
        track_lift_gap: [m] the box's bottom over the belt at the top of the lift (the rails stand 2 cm high).
        track_carry_at: the fraction of the lift after which the carry to the bin takes over, from the
            lift's state then (1: at its top); below 1 the box goes on rising as it heads for the bin instead
            of coming to a stop over the belt first.
        feed_forward_acceleration: lead the joint targets by the reference's acceleration times the
            controller's compliance (1 / kp) as well as by its speed times kd / kp, so that the arm keeps to
            its reference when it accelerates hard instead of lagging up to acceleration / kp behind it.
        wait_over_bin: on a tracking belt, when no box can be met yet after a release, wait over the bin
            instead of at the wait pose: the way to the next box is then one motion, from rest over the bin to
            over the box moving with it, instead of two (to rest at the wait pose, then on to the box).
        turn_to_box: turn the cup to the box's yaw as seen by the sensor; False keeps the cup at its home
            yaw over every box (the 60 mm pad seals on a cube turned any way), so a turned box's demo moves
            the wrist as an unturned one's does.
    """

    motion: MotionConfig = field(default_factory=MotionConfig)
    perception: PerceptionConfig = field(default_factory=PerceptionConfig)
    carry_z: float = 0.60
    approach_gap: float = 0.04
    touch_clearance: float = 0.01
    touch_speed: float = 0.12
    touch_floor: float = 0.01
    press: float = 0.0
    drop_clearance: float = 0.12
    wait_offset_y: float = 0.205
    drop_slots: int = 4
    drop_spread: float = 1.0
    wait_tolerance: float = 0.02
    approach_tolerance: float = 0.01
    lift_tolerance: float = 0.05
    drop_tolerance: float = 0.03
    release_time: float = 0.15
    sensor_image_size: int = 128
    track_hold_time: float = 0.0
    track_lift_time: float = 0.15
    track_lift_gap: float = 0.05
    track_carry_at: float = 1.0
    feed_forward_acceleration: bool = False
    wait_over_bin: bool = False
    turn_to_box: bool = True

    def __post_init__(self) -> None:
        check_range("carry_z", self.carry_z, 0.4, 1.2)
        check_range("approach_gap", self.approach_gap, 0.0, 0.2)
        check_range("touch_clearance", self.touch_clearance, 0.0, 0.1)
        check_range("touch_speed", self.touch_speed, 0.01, 0.5)
        check_range("touch_floor", self.touch_floor, 0.0, 0.04)
        check_range("drop_clearance", self.drop_clearance, 0.0, 0.5)
        check_range("wait_offset_y", self.wait_offset_y, 0.0, 0.5)
        check_range("drop_slots", self.drop_slots, 1, 12)
        check_range("drop_spread", self.drop_spread, 0.0, 1.0)
        for name in ("wait_tolerance", "approach_tolerance", "lift_tolerance", "drop_tolerance"):
            check_range(name, getattr(self, name), 0.001, 0.5)
        check_range("release_time", self.release_time, 0.0, 5.0)
        check_range("sensor_image_size", self.sensor_image_size, 16, 1024)
        check_range("press", self.press, 0.0, 0.02)
        check_range("track_hold_time", self.track_hold_time, 0.0, 2.0)
        check_range("track_lift_time", self.track_lift_time, 0.05, 2.0)
        check_range("track_lift_gap", self.track_lift_gap, 0.03, 0.3)
        check_range("track_carry_at", self.track_carry_at, 0.5, 1.0)


STOPPING_EXPERT = ExpertConfig()
# On the never-stopping belt every tenth of a second of the cycle counts (tracking-fast brings a box every
# 2 s): the cup leaves the bin as soon as the seal is gone (the box falls free of a cup moving up and
# away), it lifts the box faster (benchmarks/bench_tracking.py measures the result), and the
# carry takes over halfway up, where the lift's acceleration passes through zero as ruckig's starts. It plans
# at each joint's own acceleration (its maker's, else what its motor gives it: expert/limits.py) and leads its
# targets by the planned acceleration too, so the arm keeps up with such plans. After a release with no box yet
# within reach it waits over the bin, and it drops into each bin's two quickest slots (a bin holds at most three
# boxes between emptyings, so two at most land on one spot; benchmarks/soak.py places 2,000 of 2,000).
TRACKING_EXPERT = ExpertConfig(motion=MotionConfig(acceleration=None, jerk=1500.0), release_time=0.0,
                               touch_speed=0.16, track_lift_time=0.08, track_carry_at=0.5,
                               feed_forward_acceleration=True, wait_over_bin=True, drop_slots=2)


def expert_preset(tracking: bool) -> ExpertConfig:
    """The expert's settings for a belt: ``TRACKING_EXPERT`` on a tracking one, ``STOPPING_EXPERT`` otherwise."""
    return TRACKING_EXPERT if tracking else STOPPING_EXPERT


# the settings a demo recipe may change by name: the numeric ones (the nested limits and thresholds, and the
# switches, keep their presets; ``turn_to_box`` has its own flag)
CHANGEABLE = tuple(f.name for f in fields(ExpertConfig) if f.type in ("float", "int"))


def recording_expert(tracking: bool, turn_to_box: bool, changes: tuple[tuple[str, float], ...]) -> ExpertConfig:
    """The expert a collection or DAgger's labels use: the belt's preset, ``turn_to_box`` and the ``changes``."""
    return changed(replace(expert_preset(tracking), turn_to_box=turn_to_box), changes)


def changed(config: ExpertConfig, changes: tuple[tuple[str, float], ...]) -> ExpertConfig:
    """``config`` with the (name, value) ``changes`` made, each checked as the dataclass checks it.

    Raises:
        ConfigError: a name not in ``CHANGEABLE`` (the message lists them), a name given twice, or a value out of
            its range.
    """
    names = [name for name, _ in changes]
    unknown = sorted(set(names) - set(CHANGEABLE))
    if unknown:
        raise ConfigError(f"expert settings {unknown} cannot be changed; valid names: {list(CHANGEABLE)}")
    if len(set(names)) != len(names):
        raise ConfigError(f"expert settings {names}: give each name once")
    kinds = {f.name: f.type for f in fields(ExpertConfig)}
    fractional = [name for name, value in changes if kinds[name] == "int" and value != int(value)]
    if fractional:
        raise ConfigError(f"expert settings {fractional} are whole numbers")
    values: dict[str, Any] = {name: int(value) if kinds[name] == "int" else float(value) for name, value in changes}
    return replace(config, **values)


def parse_changes(text: str) -> tuple[tuple[str, float], ...]:
    """``"press:0.01,track_hold_time:0.15"`` as ((name, value), ...); names are checked by ``changed``."""
    pairs = []
    for part in text.split(","):
        name, sep, value = part.partition(":")
        try:
            if not sep:
                raise ValueError(part)
            pairs.append((name.strip(), float(value)))
        except ValueError:
            raise ConfigError(f"expert changes {text!r}: give NAME:VALUE pairs, comma-separated, e.g. "
                              f"press:0.01,track_hold_time:0.15 (names: {list(CHANGEABLE)})") from None
    return tuple(pairs)


def changes_text(changes: tuple[tuple[str, float], ...]) -> str:
    """The command-line value ``parse_changes`` turns back into ``changes``: ``"press:0.01,track_hold_time:0.15"``."""
    return ",".join(f"{name}:{value:g}" for name, value in changes)
