"""The conveyor cell as a robosuite ``Arena``: belt, ray sensor, three bins, cameras and a box pool.

The belt: MuJoCo 3.9 has no moving-surface primitive, so the belt is a box geom on a slide
joint along x. The task sets the joint's velocity to the belt speed before every physics step
and its position back to 0, so the surface never travels but every contact sees it moving:
MuJoCo's friction acts on relative contact velocity, so boxes resting on it are carried by
friction at the belt's speed, and stop with it.

The box pool: boxes are allocated here, parked below the floor with collisions off and gravity
compensated; the task brings one to the belt when it spawns and parks it again when it leaves.
"""

from __future__ import annotations

import numpy as np
from robosuite.models.arenas import Arena
from robosuite.utils.mjcf_utils import new_body, new_element, new_geom, new_joint, new_site

from colorsort.config import BIN_COLORS, COLORS, CellLayout
from colorsort.paths import asset_path

BELT_MASS_KG = 50.0  # heavy, so contact impulses within one step barely change its set velocity
PARK_Z = -2.0  # parked boxes wait this far below the floor


def park_position(index: int) -> tuple[float, float, float]:
    """Where pooled box ``index`` waits while parked [m]: in a row below the floor."""
    return (3.0 + 0.2 * index, 0.0, PARK_Z)


def look_at_quat(pos: np.ndarray, target: np.ndarray) -> np.ndarray:
    """MuJoCo (w, x, y, z) quaternion of a camera at ``pos`` looking at ``target``, z up."""
    forward = np.asarray(target, float) - np.asarray(pos, float)
    z_cam = -forward / np.linalg.norm(forward)
    x_cam = np.cross([0.0, 0.0, 1.0], z_cam)
    if np.linalg.norm(x_cam) < 1e-9:  # looking straight down: image up is world +y
        x_cam = np.array([1.0, 0.0, 0.0])
    x_cam /= np.linalg.norm(x_cam)
    y_cam = np.cross(z_cam, x_cam)
    R = np.stack([x_cam, y_cam, z_cam], axis=1)
    w = np.sqrt(max(1e-12, 1.0 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    return np.array([w, (R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w), (R[1, 0] - R[0, 1]) / (4 * w)])


class ConveyorArena(Arena):
    """Floor, conveyor with ray sensor, three coloured bins, cameras and ``pool_size`` boxes.

    Args:
        layout: where everything stands [m].
        pool_size: number of boxes allocated in the model.
        box_mass: mass of each box [kg].
    """

    def __init__(self, layout: CellLayout, pool_size: int, box_mass: float):
        super().__init__(asset_path("arena", "conveyor_arena.xml"))
        self.layout = layout
        self.pool_size = pool_size
        self.box_names = [f"box{i}" for i in range(pool_size)]
        self._add_conveyor()
        self._add_bins()
        self._add_cameras()
        self._add_boxes(box_mass)

    def _add_conveyor(self) -> None:
        L = self.layout
        length = L.belt_start_x - L.belt_end_x
        cx = (L.belt_start_x + L.belt_end_x) / 2
        half_w = L.belt_width / 2
        belt = new_body(name="belt", pos=(cx, L.belt_y, L.belt_top_z - 0.01))
        belt.append(new_element("inertial", None, pos=(0, 0, 0), mass=BELT_MASS_KG, diaginertia=(1.0, 1.0, 1.0)))
        belt.append(new_joint(name="belt_slide", type="slide", axis="1 0 0", damping="0", armature="0"))
        belt.append(
            new_geom(name="belt_surface", type="box", size=(length / 2, half_w, 0.01), group=1, material="belt_mat",
                     friction="1.0 0.005 0.0001")
        )
        self.worldbody.append(belt)
        # Frame under the belt and the legs: visual only (the belt carries the boxes).
        frame_h = L.belt_top_z - 0.02
        self.worldbody.append(
            new_geom(name="conveyor_frame", type="box", size=(length / 2 + 0.03, half_w + 0.02, 0.04),
                     pos=(cx, L.belt_y, frame_h - 0.04), group=1, material="frame_mat", contype=0, conaffinity=0)
        )
        for i, x in enumerate((L.belt_end_x + 0.05, cx, L.belt_start_x - 0.05)):
            for j, dy in enumerate((-half_w, half_w)):
                self.worldbody.append(
                    new_geom(name=f"conveyor_leg{i}{j}", type="box", size=(0.02, 0.02, (frame_h - 0.08) / 2),
                             pos=(x, L.belt_y + dy, (frame_h - 0.08) / 2), group=1, material="frame_mat",
                             contype=0, conaffinity=0)
                )
        # Side rails just above the belt, 2 mm clear of it, lower than the sensor ray.
        for side, sign in (("right", -1), ("left", 1)):
            self.worldbody.append(
                new_geom(name=f"rail_{side}", type="box", size=(length / 2, 0.01, 0.02),
                         pos=(cx, L.belt_y + sign * (half_w + 0.012), L.belt_top_z), group=1, material="frame_mat")
            )
        # Ray proximity sensor: a rangefinder site on the right rail, its z axis across the belt (+y).
        sensor_pos = (L.sensor_x, L.belt_y - half_w - 0.03, L.belt_top_z + L.sensor_height)
        self.worldbody.append(
            new_geom(name="sensor_housing", type="box", size=(0.015, 0.008, 0.015), pos=sensor_pos, group=1,
                     material="sensor_mat", contype=0, conaffinity=0)
        )
        self.worldbody.append(
            new_site(name="ray_sensor", pos=sensor_pos, quat=(0.7071068, -0.7071068, 0, 0), size=(0.005,),
                     rgba=(1, 0, 0, 0.5), type="sphere")
        )
        self.sensor.append(new_element("rangefinder", name="ray", site="ray_sensor"))

    def _add_bins(self) -> None:
        L = self.layout
        sx, sy, sz = (s / 2 for s in L.bin_size)
        t = L.bin_wall / 2
        for k, color in enumerate(BIN_COLORS):
            x, y = L.bin_center(k)
            body = new_body(name=f"bin_{color}", pos=(x, y, 0))
            rgba = COLORS[color]
            parts = {
                "bottom": ((sx, sy, t), (0, 0, t)),
                "wall_xn": ((t, sy, sz), (-sx + t, 0, sz)),
                "wall_xp": ((t, sy, sz), (sx - t, 0, sz)),
                "wall_yn": ((sx, t, sz), (0, -sy + t, sz)),
                "wall_yp": ((sx, t, sz), (0, sy - t, sz)),
            }
            for part, (size, pos) in parts.items():
                body.append(new_geom(name=f"bin_{color}_{part}", type="box", size=size, pos=pos, rgba=rgba, group=1,
                                     material="matte"))
            self.worldbody.append(body)

    def _add_cameras(self) -> None:
        L = self.layout
        scene_pos = np.array([1.65, -1.45, 1.30])
        scene_target = np.array([0.50, -0.05, 0.32])
        px, py, pz = L.pick_point
        sensor_cam = np.array([px, py, L.belt_top_z + 0.55])
        for name, pos, quat, fovy in (
            ("scene", scene_pos, look_at_quat(scene_pos, scene_target), 45),
            ("sensor", sensor_cam, np.array([1.0, 0.0, 0.0, 0.0]), 45),
            ("snapshot", sensor_cam, np.array([1.0, 0.0, 0.0, 0.0]), 45),  # the sensor's triggered photo
        ):
            self.worldbody.append(new_element("camera", name=name, pos=pos, quat=quat, mode="fixed", fovy=fovy))

    def _add_boxes(self, box_mass: float) -> None:
        half = self.layout.box_size / 2
        for i, name in enumerate(self.box_names):
            # gravcomp="1" at compile time keeps MuJoCo's gravity-compensation pass enabled;
            # the task switches it off per box while the box is in play.
            body = new_body(name=name, pos=park_position(i), gravcomp="1")
            inertia = box_mass * self.layout.box_size**2 / 6  # solid cube
            body.append(new_element("inertial", None, pos=(0, 0, 0), mass=box_mass, diaginertia=(inertia,) * 3))
            body.append(new_joint(name=f"{name}_joint", type="free", damping="0"))
            body.append(
                new_geom(name=f"{name}_geom", type="box", size=(half, half, half), group=1, rgba=COLORS["red"],
                         friction="1.0 0.005 0.0001", condim=4, contype=0, conaffinity=0, material="matte")
            )
            self.worldbody.append(body)
