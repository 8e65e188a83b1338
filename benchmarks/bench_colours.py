"""The colour sensor's taught classes against every colour the protocol shows it: the table of distances.

    python benchmarks/bench_colours.py

A box of each colour (the three classes; each class shaded toward either neighbour at every ``box-shade``
level; the ``distractors`` variant's yellow and purple; the ``novel-distractors`` white, black and cyan) stands
at the pick point, photographed by the sensor camera (128 px) under the cell's lights and under the light
changes the protocol makes (the ``lighting`` variant's dimmest and brightest, warm and cold; ``light-color``'s
tints at each level, the lamps turned as it turns them). Each cell of the table is the nearest class to the
mean of the box's top face, after the sensor's light correction, and its distance (CIE76 delta E at the class's
lightness, ``colour_classes.ColourClasses.distances``), then the sensor's reading of the whole photo (a class,
``unknown``, or ``-``: nothing seen). Last, the margins: the farthest a class's colour (a shade) lies from it,
and the nearest any other colour comes to a class, under the cell's lights, against ``tolerance``.
"""

from __future__ import annotations

import argparse

import mujoco
import numpy as np

from colorsort.config import BIN_COLORS, COLORS, NOVEL_COLORS, Lighting
from colorsort.envs.robosuite_task import ColorSort
from colorsort.expert.perception import CameraModel, ColorSensor
from colorsort.expert.teach import face_mask
from colorsort.results import recorded
from colorsort.shifts.box_shade import BoxShade, shade
from colorsort.shifts.light_color import LightColor, tint


def palette() -> dict[str, tuple[str, tuple[float, ...]]]:
    """Row name -> (the class it belongs to, or "" for none; rgba)."""
    rows: dict[str, tuple[str, tuple[float, ...]]] = {c: (c, COLORS[c]) for c in BIN_COLORS}
    for level, distance in enumerate(BoxShade.magnitudes, start=1):
        for c in BIN_COLORS:
            for which, toward in enumerate(("a", "b")):
                rows[f"{c} shade {level}{toward}"] = (c, shade(c, distance, which))
    rows.update({c: ("", COLORS[c]) for c in COLORS if c not in BIN_COLORS})
    rows.update({c: ("", rgba) for c, rgba in NOVEL_COLORS.items()})
    return rows


def conditions() -> dict[str, tuple[Lighting, float]]:
    """Column name -> (the lights, the lamps' turn [deg])."""
    out = {"cell": (Lighting(), 0.0), "dim 0.5": (Lighting(brightness=0.5), 0.0),
           "bright 1.6": (Lighting(brightness=1.6), 0.0), "warm": (Lighting(tint=(1.0, 0.80, 0.60)), 0.0),
           "cold": (Lighting(tint=(0.70, 0.85, 1.0)), 0.0)}
    for level, (strength, turn) in enumerate(LightColor.magnitudes, start=1):
        for hue in ("green", "magenta"):
            out[f"{hue} {level}"] = (Lighting(tint=tuple(float(c) for c in tint(strength, hue))), turn)
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--size", type=int, default=128, help="photo side [px]")
    args = p.parse_args()
    env = ColorSort(robots="IRB140", preset="default", spawn_period=600.0, has_offscreen_renderer=True,
                    use_camera_obs=False, seed=0)
    env.reset()
    camera = CameraModel.from_sim(env.mj_model, env.mj_data, "sensor", args.size, args.size)
    sensor = ColorSensor(camera, env.layout)
    classes, m = sensor.classes, env.mj_model
    directions = m.light_dir.copy()
    px, py, top = env.layout.pick_point
    face_pixels = face_mask(camera, (px, py, top), 0.0, env.layout.box_size)
    rows, columns = palette(), conditions()
    table: dict[str, list[str]] = {name: [] for name in rows}
    inside, outside = 0.0, np.inf
    for column, (lighting, turn) in columns.items():
        env.plant.set_lighting(lighting)
        q = np.zeros(4)
        mujoco.mju_axisAngle2Quat(q, np.array([np.cos(1.0), np.sin(1.0), 0.0]), np.deg2rad(turn))
        for light in range(m.nlight):
            mujoco.mju_rotVecQuat(m.light_dir[light], directions[light].copy(), q)
        for name, (member, rgba) in rows.items():
            for box in env.boxes_in_play():
                env.remove_box(box)
            env.plant.pool.palette["yellow"] = rgba  # any name the pool can place
            env.put_box("yellow", px, py)
            env.sim.forward()
            image = env.camera_image("sensor", args.size, args.size)
            face = np.mean(sensor.light_corrected(image)[face_pixels], axis=0)
            d = classes.distances(face)
            k = int(np.argmin(d))
            seen = sensor.box_at_sensor(image)
            table[name].append(f"{classes.names[k]} {d[k]:.1f}, read {seen.color if seen else '-'}")
            if column == "cell":
                own = d[classes.names.index(member)] if member else np.inf
                inside = max(inside, own) if member else inside
                outside = min(outside, min(d[j] for j, c in enumerate(classes.names) if c != member))
    env.close()
    print(f"nearest class to each box's top face and its distance [delta E, CIE76, at the class's lightness], then "
          f"the sensor's reading; {args.size} px photos; tolerance {sensor.config.tolerance:g}")
    print("| colour | " + " | ".join(columns) + " |")
    print("| --- |" + " --- |" * len(columns))
    for name, cells in table.items():
        print(f"| {name} | " + " | ".join(cells) + " |")
    print(f"\nunder the cell's lights: the farthest a class's own colour lies from it {inside:.1f}; the nearest any "
          f"other colour comes to a class {outside:.1f}; tolerance {sensor.config.tolerance:g}")


if __name__ == "__main__":
    with recorded(__file__):
        main()
