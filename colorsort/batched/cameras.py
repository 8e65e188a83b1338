"""The cell's cameras on the batched cell: MuJoCo Warp's ray-traced renderer, every world at once.

Images come out as the CPU cell's do (``cell/cameras.py``): (N, H, W, 3) uint8 RGB, right side up, one
torch tensor per camera on the cell's device; ``snapshot`` holds the sensor's view taken when the ray
starts seeing a box (``cell/snapshot.py``), black before the first.

Colour: the boxes and the bins are coloured by ``geom_rgba`` under a shared white material; MuJoCo's
OpenGL renderer shows the geom's colour, MuJoCo Warp's the material's (white). ``warp_matids`` gives
those geoms no material on the device, so Warp reads ``geom_rgba`` too. What still differs (lights,
shading) is measured by ``benchmarks/bench_render_parity.py``.
"""

from __future__ import annotations

import mujoco
import mujoco_warp as mjw
import numpy as np
import warp as wp

from colorsort.cell.cameras import CAMERAS, mjcf_name
from colorsort.cell.snapshot import SNAPSHOT, SOURCE
from colorsort.errors import UnknownName

VISIBLE_GROUPS = [1, 2]  # robosuite's off-screen renderer hides group 0, the collision geoms
DEFAULT_RGBA = np.array([0.5, 0.5, 0.5, 1.0], np.float32)  # MuJoCo's geom rgba when none is given


def warp_matids(model: mujoco.MjModel) -> np.ndarray:
    """``geom_matid`` for MuJoCo Warp: -1 (no material) for every geom whose own rgba is set, so that
    Warp draws the colour OpenGL draws; textured and plain material geoms keep their material."""
    matid = model.geom_matid.copy()
    own = np.any(np.abs(model.geom_rgba - DEFAULT_RGBA) > 1e-6, axis=1)
    untextured = np.array([m < 0 or model.mat_texid[m].max() < 0 for m in matid])
    matid[own & untextured] = -1
    return matid


class BatchedCameras:
    """Renders ``cameras`` at ``size`` (height, width) [px] for every world.

    Args:
        model: the compiled host model (the render context is built from it).
        worlds: worlds rendered at once.
        cameras: ColorSort camera names (``scene``, ``sensor``, ``wrist``, ``snapshot``).
        size: (height, width) [px].
    """

    def __init__(self, model: mujoco.MjModel, worlds: int, cameras: tuple[str, ...], size: tuple[int, int]):
        import torch

        unknown = [c for c in cameras if c not in CAMERAS]
        if unknown:
            raise UnknownName("camera(s)", unknown, list(CAMERAS), "cameras")
        self.cameras, self.size, self.worlds = tuple(cameras), tuple(size), worlds
        live = {SOURCE if c == SNAPSHOT else c for c in cameras}
        names = [model.camera(i).name for i in range(model.ncam)]
        active = [n in {mjcf_name(c) for c in live} for n in names]
        self.index = {c: sum(active[: names.index(mjcf_name(c))]) for c in live}  # in the render buffers
        h, w = self.size
        self.context = mjw.create_render_context(model, nworld=worlds, cam_res=(w, h), render_rgb=True,
                                                 render_depth=False, cam_active=active, use_shadows=False,
                                                 enabled_geom_groups=VISIBLE_GROUPS, render_skybox=True)
        self.buffers = {c: wp.zeros((worlds, h, w), dtype=wp.vec3) for c in live}
        device = wp.get_device()
        self.torch_device = torch.device("cpu" if device.is_cpu else f"cuda:{device.ordinal}")
        self.held = torch.zeros((worlds, h, w, 3), dtype=torch.uint8, device=self.torch_device)
        self.saw_box = torch.zeros(worlds, dtype=torch.bool, device=self.torch_device)

    def clear(self, worlds) -> None:
        """New episodes in ``worlds`` (a torch index): the snapshot black, no box seen."""
        self.held[worlds] = 0
        self.saw_box[worlds] = False

    def render(self, m, d, detected) -> dict:
        """Every camera now, after ``detected`` (N,) bool (the ray sees a box) is observed."""
        import torch

        mjw.refit_bvh(m, d, self.context)
        mjw.render(m, d, self.context)
        for camera, index in self.index.items():
            mjw.get_rgb(self.context, index, self.buffers[camera])
        wp.synchronize_device()  # Warp's stream is not torch's
        live = {c: (wp.to_torch(b).clamp(0, 1) * 255 + 0.5).to(torch.uint8) for c, b in self.buffers.items()}
        if SNAPSHOT in self.cameras:
            rising = detected & ~self.saw_box
            self.held[rising] = live[SOURCE][rising]
            self.saw_box = detected.clone()
        return {c: (self.held.clone() if c == SNAPSHOT else live[c]) for c in self.cameras}
