"""The colour sensor: a downward camera image -> box colour, position on the belt and yaw, with OpenCV.

Only the image, the camera's calibration (intrinsics and pose) and the cell's nominal geometry
are used; never the simulator's geom colours or poses. The pipeline:

1. blur (sensor noise), undo a change of light measured on the rails and the belt (``colour_classes.py``);
2. keep saturated, not-too-dark pixels inside the belt's region of interest: the belt is dark
   grey and the rails light grey, so only boxes survive;
3. label each pixel by the nearest colour class taught from sample parts (``teach.py``): a region
   of CIELAB, compared at the class's lightness so that shading does not count (anything else is
   "unknown"), so that touching boxes of different colours come apart;
4. connected components per label; a component about twice a box's area is split with k-means;
5. per component: the minimum-area rectangle's centre and the outline's mean direction (on the
   quarter-turn circle) give centre and yaw, back-projected through the camera onto the plane
   of the boxes' top faces.

Seen from straight above, a box within half its size of the optical axis shows only its top
face (its sides are hidden behind it), so the rectangle is the top face itself.
"""

from __future__ import annotations

import colorsys
from dataclasses import dataclass, field

import cv2
import numpy as np

from colorsort.config import BIN_COLORS, COLORS, CellLayout, check_range
from colorsort.errors import ConfigError, UnknownName
from colorsort.expert.colour_classes import ColourClasses, TaughtColours

UNKNOWN = "unknown"


@dataclass(frozen=True)
class CameraModel:
    """A pinhole camera as MuJoCo renders it, images right side up (row 0 at the top).

    Attributes:
        position: camera centre in the world [m], (3,).
        rotation: camera-to-world rotation, (3, 3); columns are the camera's x (image right),
            y (image up) and z (backwards: the camera looks along -z) axes.
        fovy: vertical field of view [deg].
        width, height: image size [px].
    """

    position: np.ndarray
    rotation: np.ndarray
    fovy: float
    width: int
    height: int

    @property
    def focal(self) -> float:
        """Focal length [px]."""
        return self.height / 2 / np.tan(np.deg2rad(self.fovy) / 2)

    @classmethod
    def from_sim(cls, model, data, name: str, width: int, height: int) -> CameraModel:
        """Calibration of camera ``name`` from a MuJoCo model and data (after ``mj_forward``)."""
        cid = model.camera(name).id
        return cls(
            position=data.cam_xpos[cid].copy(),
            rotation=data.cam_xmat[cid].reshape(3, 3).copy(),
            fovy=float(model.cam_fovy[cid]),
            width=width,
            height=height,
        )

    def pixel_to_plane(self, uv: np.ndarray, z: float) -> np.ndarray:
        """World points [m], (n, 3), where pixel rays ``uv`` (n, 2) [px, (column, row)] meet the plane at ``z``."""
        uv = np.atleast_2d(np.asarray(uv, float))
        f = self.focal
        x = (uv[:, 0] - self.width / 2) / f
        y = -(uv[:, 1] - self.height / 2) / f
        rays = np.stack([x, y, -np.ones_like(x)], axis=1) @ self.rotation.T  # (n, 3)
        t = (z - self.position[2]) / rays[:, 2]
        return self.position + t[:, None] * rays

    def polygon_mask(self, corners: np.ndarray | list) -> np.ndarray:
        """The mask (H, W) uint8 of the pixels that see the convex polygon of world ``corners`` (n, 3) [m], in order."""
        mask = np.zeros((self.height, self.width), np.uint8)
        cv2.fillConvexPoly(mask, np.round(self.world_to_pixel(np.asarray(corners, float))).astype(np.int32), 1)
        return mask

    def world_to_pixel(self, points: np.ndarray) -> np.ndarray:
        """Pixel coordinates (n, 2) [px, (column, row)] of world points (n, 3) [m]."""
        p = (np.atleast_2d(points) - self.position) @ self.rotation  # camera frame, (n, 3)
        f = self.focal
        return np.stack([self.width / 2 + f * p[:, 0] / -p[:, 2], self.height / 2 - f * p[:, 1] / -p[:, 2]], axis=1)


@dataclass(frozen=True)
class PerceptionConfig:
    """Thresholds of the colour sensor.

    Attributes:
        colors: labels the sensor reports; any other colour is "unknown". Each is a class taught from a
            sample part (``teach.py``; the cell's as built: ``colour_classes.SHIPPED``).
        tolerance: [delta E, CIE76] the largest distance of a pixel's colour, at a class's lightness, from the
            class's taught colour (``benchmarks/bench_colours.py`` gives the distances that set it).
        min_saturation: HSV saturation in [0, 1] below which a pixel is belt, rail or glare.
        min_value: HSV value in [0, 1] below which a pixel is too dark to judge.
        min_area: smallest blob kept, as a fraction of a box top face's area in the image.
    """

    colors: tuple[str, ...] = BIN_COLORS
    tolerance: float = 28.0
    min_saturation: float = 0.40
    min_value: float = 0.10
    min_area: float = 0.15

    def __post_init__(self) -> None:
        unknown = [c for c in self.colors if c not in COLORS]
        if unknown:
            raise UnknownName("colour(s)", unknown, sorted(COLORS), "colours")
        check_range("tolerance", self.tolerance, 1.0, 100.0)
        for name in ("min_saturation", "min_value", "min_area"):
            check_range(name, getattr(self, name), 0.0, 1.0)


@dataclass(frozen=True)
class Detection:
    """One box seen by the sensor.

    Attributes:
        color: a configured colour, or "unknown".
        center: centre of the box's top face in the world [m], (3,).
        yaw: rotation of the box about world z [rad], in [-pi/4, pi/4) (a cube looks the same
            every quarter turn).
        confidence: in [0, 1]: colour agreement with the class (1 - mean distance / tolerance) times the
            fraction of a full top face that is visible.
        complete: False when the box touches the edge of the view (partly in view); its
            centre and yaw are then those of the visible part only.
        area: blob area [px].
    """

    color: str
    center: np.ndarray = field(repr=False)
    yaw: float
    confidence: float
    complete: bool
    area: int


def surface_masks(camera: CameraModel, layout: CellLayout) -> tuple[np.ndarray, np.ndarray]:
    """Boolean masks (H, W) of the pixels of ``camera`` that see the rails' top faces and the belt, inside their
    edges: the references the sensor measures the light on."""
    half = layout.belt_width / 2
    xs = camera.pixel_to_plane(np.array([[0.0, camera.height / 2], [camera.width, camera.height / 2]]),
                               layout.belt_top_z)[:, 0]
    x0, x1 = xs.min() - 1, xs.max() + 1

    def strip(y0: float, y1: float, z: float) -> np.ndarray:
        mask = camera.polygon_mask([(x0, y0, z), (x0, y1, z), (x1, y1, z), (x1, y0, z)])
        return cv2.erode(mask, np.ones((3, 3), np.uint8)).astype(bool)

    y, rail = layout.belt_y, half + 0.012  # the arena's rails: 2 cm wide, their centres 12 mm outside the belt's edges
    top = layout.belt_top_z + 0.02
    rails = strip(y - rail - 0.006, y - rail + 0.006, top) | strip(y + rail - 0.006, y + rail + 0.006, top)
    return rails, strip(y - half + 0.02, y + half - 0.02, layout.belt_top_z)


def wrap_quarter_turn(angle: float) -> float:
    """``angle`` [rad] mapped into [-pi/4, pi/4): the yaw of a cube, which repeats every quarter turn."""
    return float((angle + np.pi / 4) % (np.pi / 2) - np.pi / 4)


def bin_for(t: Detection | None) -> str | None:
    """The bin a sighted box goes to: its colour when it was seen whole and its colour has a bin; else None
    (no box seen, a box partly in view, a colour with no bin): the box is let through."""
    return t.color if t is not None and t.complete and t.color in BIN_COLORS else None


def hue_of(rgb: tuple[float, ...]) -> float:
    """Hue [deg] of an RGB colour with components in [0, 1]."""
    return colorsys.rgb_to_hsv(*rgb[:3])[0] * 360.0


class ColorSensor:
    """Finds and classifies boxes in the sensor camera's images.

    Args:
        camera: the calibrated camera the images come from.
        layout: the cell's geometry: belt position, box size (sets the region of interest and
            the height of the boxes' top faces).
        config: thresholds.
        taught: the colour classes' teach (the cell's as built by default: ``TaughtColours.load()``).
    """

    def __init__(self, camera: CameraModel, layout: CellLayout, config: PerceptionConfig = PerceptionConfig(),
                 taught: TaughtColours | None = None):
        self.camera = camera
        self.layout = layout
        self.config = config
        self.top_z = layout.belt_top_z + layout.box_size
        self.classes = ColourClasses(taught or TaughtColours.load(), config.colors, config.tolerance)
        size_px = camera.focal * layout.box_size / (camera.position[2] - self.top_z)
        self.box_area_px = size_px**2
        self._roi = self._belt_roi()
        self.roi = self._roi > 0  # (H, W) where a box's top face on the belt can be
        self._roi_inner = cv2.erode(self._roi, np.ones((3, 3), np.uint8)).astype(bool)  # not on its edge
        self._kernel = np.ones((3, 3), np.uint8)
        self._min_s, self._min_v = config.min_saturation, config.min_value
        self._rails, self._belt = surface_masks(camera, layout)
        self._labels = list(config.colors) + [UNKNOWN]

    def _belt_roi(self) -> np.ndarray:
        """Mask of the pixels that can see a box's top face on the belt, (H, W) uint8.

        A top face lies within the belt's width at top-face height; seen from above, that strip
        reaches just past the rails and stops short of the bins beside the belt.
        """
        L, cam = self.layout, self.camera
        half = L.belt_width / 2
        xs = cam.pixel_to_plane(np.array([[0.0, cam.height / 2], [cam.width, cam.height / 2]]), self.top_z)[:, 0]
        corners = np.array([[x, L.belt_y + s * half, self.top_z]
                            for x in (xs.min() - 1, xs.max() + 1) for s in (-1, 1)])
        return cam.polygon_mask(corners[[0, 1, 3, 2]])

    def light_corrected(self, image: np.ndarray) -> np.ndarray:
        """``image`` (H, W, 3) uint8 as it would look under the lights the classes were taught under, as float."""
        rails, belt = (np.median(image[mask], axis=0) for mask in (self._rails, self._belt))
        return image * self.classes.light_gain(rails, belt)

    def detect(self, image: np.ndarray) -> list[Detection]:
        """Every box in view, largest first.

        Args:
            image: (H, W, 3) uint8 RGB, right side up, the size the camera model says.
        """
        cam, cfg = self.camera, self.config
        if image.shape != (cam.height, cam.width, 3) or image.dtype != np.uint8:
            raise ConfigError(f"Expected a ({cam.height}, {cam.width}, 3) uint8 image, got {image.shape} {image.dtype}")
        rgb = self.light_corrected(cv2.GaussianBlur(image, (3, 3), 0))
        hsv = cv2.cvtColor(np.clip(rgb, 0, 255).astype(np.float32) / 255, cv2.COLOR_RGB2HSV)  # S, V in [0, 1]
        valid = (hsv[..., 1] >= self._min_s) & (hsv[..., 2] >= self._min_v) & self.roi
        label_img = np.full(valid.shape, 255, np.uint8)  # (H, W): 255 where no box can be
        distance = np.full(valid.shape, cfg.tolerance)  # [delta E] to the nearest class
        label_img[valid], distance[valid] = self.classes.label(rgb[valid])  # only the pixels a box can be
        detections = []
        for k, label in enumerate(self._labels):
            mask = cv2.morphologyEx((label_img == k).view(np.uint8), cv2.MORPH_OPEN, self._kernel)
            n, comp, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=4)
            for c in range(1, n):
                if stats[c, cv2.CC_STAT_AREA] < cfg.min_area * self.box_area_px:
                    continue
                x, y, w, h = stats[c, :4]
                window = (slice(y, y + h), slice(x, x + w))
                blob = comp[window] == c
                for part in self._split(blob):
                    err = float(np.minimum(distance[window][part], cfg.tolerance).mean())
                    detections.append(self._measure(part, (x, y), label, err))
        detections.sort(key=lambda d: -d.area)
        return detections

    def box_at_sensor(self, image: np.ndarray) -> Detection | None:
        """The box nearest the pick point (the one the ray sensor stopped), or None if none is in view.

        Wholly visible boxes are preferred to those cut by the edge of the view.
        """
        px, py, _ = self.layout.pick_point
        detections = self.detect(image)
        # Boxes cut by the edge of the view (or glimpses of a bin past the belt) come last.
        candidates = [d for d in detections if d.complete] or detections
        if not candidates:
            return None
        return min(candidates, key=lambda d: np.hypot(d.center[0] - px, d.center[1] - py))

    def _split(self, blob: np.ndarray) -> list[np.ndarray]:
        """A blob of several touching same-coloured boxes, cut into one mask per box with k-means."""
        area = int(blob.sum())
        k = int(round(area / self.box_area_px))
        if k < 2:
            return [blob]
        rows, cols = np.nonzero(blob)
        pts = np.stack([cols, rows], axis=1).astype(np.float32)
        criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 20, 0.1)
        # Seeds spread along the blob's long axis make the result deterministic.
        order = np.argsort(pts @ np.linalg.svd(pts - pts.mean(0), full_matrices=False)[2][0])
        seeds = np.array([pts[order[int((i + 0.5) * len(pts) / k)]] for i in range(k)], np.float32)
        _, assign, _ = cv2.kmeans(pts, k, np.zeros((len(pts), 1), np.int32), criteria, 1,
                                  cv2.KMEANS_USE_INITIAL_LABELS, seeds)
        parts = []
        for i in range(k):
            part = np.zeros_like(blob)
            sel = assign.ravel() == i
            part[rows[sel], cols[sel]] = True
            parts.append(part)
        return parts

    def _measure(self, part: np.ndarray, offset: tuple[int, int], label: str, err: float) -> Detection:
        """Centre and yaw of one box's mask ``part``, a window of the image whose corner is at ``offset`` [px]."""
        cam, cfg = self.camera, self.config
        contours, _ = cv2.findContours(part.view(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        contour = max(contours, key=cv2.contourArea)
        rect = cv2.minAreaRect(contour)
        # The contour runs through the centres of the boundary pixels, which lie at +0.5.
        shift = np.array(offset, float) + 0.5
        # Yaw from every boundary point, not just the rectangle's extremes: the direction of the
        # outline around each point, averaged on the quarter-turn circle (angles times 4).
        outline = cam.pixel_to_plane(contour[:, 0, :] + shift, self.top_z)[:, :2]  # (n, 2)
        tangent = np.roll(outline, -3, axis=0) - np.roll(outline, 3, axis=0)
        angle = np.arctan2(tangent[:, 1], tangent[:, 0])
        weight = np.linalg.norm(tangent, axis=1)
        yaw = float(np.arctan2((weight * np.sin(4 * angle)).sum(), (weight * np.cos(4 * angle)).sum()) / 4)
        yaw = wrap_quarter_turn(yaw)
        center = cam.pixel_to_plane(np.array(rect[0]) + shift, self.top_z)[0]
        rows, cols = np.nonzero(part)
        rows, cols = rows + offset[1], cols + offset[0]
        # Partly in view: the box reaches the image border or the edge of the region of interest.
        touches = (
            rows.min() == 0 or cols.min() == 0 or rows.max() == cam.height - 1 or cols.max() == cam.width - 1
            or not self._roi_inner[rows, cols].all()
        )
        area = int(part.sum())
        agreement = max(0.0, 1.0 - err / cfg.tolerance) if label != UNKNOWN else 0.0
        confidence = agreement * min(1.0, area / self.box_area_px)
        return Detection(label, center, yaw, confidence, not touches, area)
