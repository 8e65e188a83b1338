"""What the simulator knows of a cell that none of its sensors shows: what an expert taking over a cell it did not
run is told (``Expert.take_over``; DAgger's expert labels the states a learned policy reaches)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from colorsort.cell.plant import Plant


@dataclass(frozen=True)
class BeltBox:
    """A box lying on the belt, as the simulator has it."""

    color: str
    x: float  # [m] its centre, world frame
    y: float  # [m]
    yaw: float  # [rad] about the world's z axis


@dataclass(frozen=True)
class TakeOver:
    """What an expert taking over is told besides the observation.

    Attributes:
        held: the colour of the box sealed to the cup, None when none is.
        past_the_ray: the boxes on the belt that have passed the ray (their photo is history), upstream first.
    """

    held: str | None
    past_the_ray: tuple[BeltBox, ...]


NOTHING_HELD = TakeOver(None, ())  # a cell with nothing in the cup and nothing past the ray


def take_over_view(plant: Plant) -> TakeOver:
    """The held box's colour and the boxes on the belt past the ray, now, in the cell ``plant`` (a ``ColorSort``
    env's ``plant``)."""
    pool, seal = plant.pool, plant.seal
    layout = pool.layout
    held = None if seal.held is None else pool.boxes[seal.held].color
    on_belt = []
    for box in pool.in_play():
        if box.index == seal.held:
            continue
        x, y, z, qw, qx, qy, qz = (float(v) for v in pool.pose(box))
        half = layout.box_size / 2
        lying = abs(z - (layout.belt_top_z + pool.height(box) / 2)) < 0.01  # not falling, not on its side
        if lying and x + half < layout.sensor_x:  # the belt carries boxes toward -x; its trailing face is past
            yaw = float(np.arctan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz)))
            on_belt.append(BeltBox(box.color, x, y, yaw))
    return TakeOver(held, tuple(sorted(on_belt, key=lambda b: -b.x)))
