"""The colour sensor's teach step, run once for the cell as built, as an integrator teaches a colour sensor.

Under the cell's own lights, a sample part of each class is set on the belt at the pick point, a few times
(centred, 3 cm off the centre line either way, turned 30 degrees), and photographed by the sensor camera;
the class's colour is the CIELAB colour of the mean of its top face's pixels (1 cm inside its edges) over
those photos, and
the rails' and belt's colours (their medians) are taken from the same photos. The sensor
(``perception.ColorSensor``) reads the result from ``colour_classes.SHIPPED``:

    python -m colorsort.expert.teach          # print what it teaches
    python -m colorsort.expert.teach --write  # and write it where the sensor reads it

The same code gives the same numbers (``tests/test_perception.py`` holds the shipped file to it).
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from colorsort.config import BIN_COLORS
from colorsort.expert.colour_classes import SHIPPED, TaughtColours, triple
from colorsort.expert.perception import CameraModel, surface_masks
from colorsort.shifts.colour import lab_of_linear, linear

PLACEMENTS = ((0.0, 0.0), (0.03, 0.0), (-0.03, 0.0), (0.0, 30.0))  # (offset from the centre line [m], yaw [deg])


def teach(size: int = 128, classes: tuple[str, ...] = BIN_COLORS) -> TaughtColours:
    """Photograph a sample of each of ``classes`` at the pick point of a fresh default cell (IRB 140, lights as
    built) with the sensor camera at ``size`` x ``size`` px, and learn their colours."""
    from colorsort.envs.robosuite_task import ColorSort

    env = ColorSort(robots="IRB140", preset="default", spawn_period=600.0, has_offscreen_renderer=True,
                    use_camera_obs=False, seed=0)
    try:
        env.reset()
        camera = CameraModel.from_sim(env.mj_model, env.mj_data, "sensor", size, size)
        rails_mask, belt_mask = surface_masks(camera, env.layout)
        px, py, top = env.layout.pick_point
        centres, rails, belt = {}, [], []
        for name in classes:
            pixels = []
            for dy, yaw in PLACEMENTS:
                for box in env.boxes_in_play():
                    env.remove_box(box)
                env.put_box(name, px, py + dy, np.deg2rad(yaw))
                env.sim.forward()
                image = env.camera_image("sensor", size, size)
                pixels.append(image[face_mask(camera, (px, py + dy, top), np.deg2rad(yaw), env.layout.box_size)])
                rails.append(np.median(image[rails_mask], axis=0))
                belt.append(np.median(image[belt_mask], axis=0))
            mean = linear(np.concatenate(pixels) / 255.0).mean(axis=0)
            centres[name] = triple(lab_of_linear(mean))
        return TaughtColours(centres, triple(np.mean(rails, axis=0)), triple(np.mean(belt, axis=0)), size)
    finally:
        env.close()


def face_mask(camera: CameraModel, center: tuple[float, float, float], yaw: float, edge: float,
              inset: float = 0.01) -> np.ndarray:
    """The mask (H, W) of the pixels that see a square top face of side ``edge`` [m] centred at ``center`` [m],
    turned ``yaw`` [rad], ``inset`` [m] inside its edges (no edge pixel, half belt, counts)."""
    h = edge / 2 - inset
    c, s = np.cos(yaw), np.sin(yaw)
    return camera.polygon_mask([(center[0] + c * u - s * v, center[1] + s * u + c * v, center[2])
                                for u, v in ((-h, -h), (h, -h), (h, h), (-h, h))]).astype(bool)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description="Teach the colour sensor its classes from sample parts.")
    p.add_argument("--size", type=int, default=128, help="photo side [px]")
    p.add_argument("--write", action="store_true", help=f"write the result to {SHIPPED}")
    args = p.parse_args(argv)
    taught = teach(args.size)
    print(json.dumps(taught.to_json(), indent=1))
    if args.write:
        taught.save()
        print(f"written: {SHIPPED}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
