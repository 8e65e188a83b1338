"""The colour sensor on rendered views: colours under changing light, unknown colours, localisation."""

import numpy as np
import pytest
from helpers import new_env
from studies.sensor_views import ViewSampler, wrap_quarter_turn

from colorsort.cell.lighting import CONDITIONS, LightRig
from colorsort.config import BIN_COLORS, NOVEL_COLORS, Lighting
from colorsort.expert.perception import UNKNOWN, ColorSensor, PerceptionConfig


@pytest.fixture(scope="module")
def sampler():
    env = new_env(has_offscreen_renderer=True, camera_names=["sensor"])
    env.reset()
    yield ViewSampler(env, 128, 128)
    env.close()


@pytest.fixture(scope="module")
def sensor(sampler):
    return ColorSensor(sampler.camera, sampler.env.layout)


@pytest.mark.parametrize("condition", ["normal", "dim", "bright", "warm", "cold", "noise", "shadow"])
def test_labels_and_locates_each_colour(sampler, sensor, condition):
    rng = np.random.default_rng(7)
    for color in ("red", "green", "blue"):
        for _ in range(4):
            view = sampler.sample(color, CONDITIONS[condition], "single", rng)
            det = sensor.box_at_sensor(view.image)
            assert det is not None and det.color == color and det.complete
            assert np.linalg.norm(det.center[:2] - view.center[:2]) < 0.005
            assert abs(np.rad2deg(wrap_quarter_turn(det.yaw - view.yaw))) < 3.0
            # at twice the cell's light the renderer clips the faces' brightest channel: read at the class's edge
            assert (0.0 if condition == "bright" else 0.5) < det.confidence <= 1.0


@pytest.mark.parametrize("color", ["yellow", "purple"])
@pytest.mark.parametrize("condition", ["normal", "dim", "bright", "warm", "cold"])
def test_colour_without_a_bin_is_unknown(sampler, sensor, color, condition):
    rng = np.random.default_rng(3)
    for _ in range(3):
        det = sensor.box_at_sensor(sampler.sample(color, CONDITIONS[condition], "single", rng).image)
        assert det is not None and det.color == UNKNOWN


@pytest.fixture
def palette(sampler):
    """The sampler's box colours, restored after the test."""
    palette = sampler.env.plant.pool.palette
    before = dict(palette)
    yield palette
    palette.clear()
    palette.update(before)


@pytest.mark.parametrize("level", [1, 2, 3])
def test_every_box_shade_is_read_as_its_class(sampler, sensor, palette, level):
    """``box-shade``: each class colour shaded toward either neighbour at each level is still its class."""
    from colorsort.shifts.box_shade import BoxShade, shade

    rng = np.random.default_rng(level)
    for color in BIN_COLORS:
        for which in (0, 1):
            palette[color] = shade(color, BoxShade.magnitudes[level - 1], which)
            for _ in range(2):
                det = sensor.box_at_sensor(sampler.sample(color, CONDITIONS["normal"], "single", rng).image)
                assert det is not None and det.color == color, (color, which, det)


@pytest.mark.parametrize("novel", sorted(NOVEL_COLORS))
def test_a_novel_colour_is_no_class(sampler, sensor, palette, novel):
    """``novel-distractors``: white, black and cyan boxes are read as no class (or not seen: white and black are
    as unsaturated as the belt)."""
    palette["yellow"] = NOVEL_COLORS[novel]  # painted on a box the sampler can place
    rng = np.random.default_rng(2)
    for _ in range(3):
        det = sensor.box_at_sensor(sampler.sample("yellow", CONDITIONS["normal"], "single", rng).image)
        assert det is None or det.color == UNKNOWN, det


@pytest.mark.parametrize("hue", ["green", "magenta"])
def test_lights_tinted_as_light_color_tints_them_leave_every_class_its_own(sampler, sensor, hue):
    """``light-color`` level 3's tint (0.45): corrected on the rails and the belt, each class is read as itself."""
    from colorsort.shifts.light_color import tint

    lighting = Lighting(tint=tuple(float(c) for c in tint(0.45, hue)))
    rng = np.random.default_rng(4)
    for color in BIN_COLORS:
        for _ in range(2):
            det = sensor.box_at_sensor(sampler.sample(color, lighting, "single", rng).image)
            assert det is not None and det.color == color and det.confidence > 0.5, (color, det)


def test_picks_the_box_at_the_sensor_when_two_are_in_view(sampler, sensor):
    rng = np.random.default_rng(11)
    for color in ("red", "green", "blue"):
        view = sampler.sample(color, CONDITIONS["normal"], "two_boxes", rng, other_colors=("blue", "red"))
        det = sensor.box_at_sensor(view.image)
        assert det.color == color
        assert np.linalg.norm(det.center[:2] - view.center[:2]) < 0.005
        assert len(sensor.detect(view.image)) == 2


def test_box_partly_in_view_is_named_and_flagged(sampler, sensor):
    rng = np.random.default_rng(5)
    for color in ("red", "green", "blue"):
        view = sampler.sample(color, CONDITIONS["normal"], "partial", rng)
        (det,) = sensor.detect(view.image)
        assert det.color == color and not det.complete


def test_empty_belt_has_no_detection(sampler, sensor):
    for box in sampler.env.boxes_in_play():
        sampler.env.remove_box(box)
    sampler.env.sim.forward()
    image = np.ascontiguousarray(sampler.env.sim.render(camera_name="sensor", width=128, height=128)[::-1])
    assert sensor.detect(image) == [] and sensor.box_at_sensor(image) is None


def test_light_rig_changes_lights_and_restores_them(sampler):
    model = sampler.env.mj_model
    before = model.light_diffuse.copy()
    rig = LightRig(model)
    rig.apply(Lighting(brightness=0.5, tint=(1.0, 0.8, 0.6)))
    assert np.allclose(model.light_diffuse, before * 0.5 * np.array([1.0, 0.8, 0.6]))
    rig.restore()
    assert np.allclose(model.light_diffuse, before)


def test_bad_input_raises(sensor):
    with pytest.raises(ValueError, match="uint8 image"):
        sensor.detect(np.zeros((64, 64, 3), np.uint8))
    with pytest.raises(ValueError, match="Valid colours"):
        PerceptionConfig(colors=("red", "pink"))
    with pytest.raises(ValueError, match="brightness"):
        Lighting(brightness=0.0)
