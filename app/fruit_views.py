"""Views of a fruit for a vision dataset: random cameras, lights and stages, exact instance masks.

:func:`sample_views` draws the views of one fruit from its random generator;
:class:`ViewRenderer` renders each view twice with the same camera:

* the **picture**: the fruit's surface coloured per cell (smooth shading, a key and a
  fill light, a little gloss), on its stage: ``plain`` (a backdrop colour), ``conveyor``
  (the fruit lies on a belt) or ``cup`` (the fruit sits in a cup on the belt);
* the **id pass**: lighting, shading and anti-aliasing off, every surface face painted
  with its index + 1 as a 24-bit colour, the stage in black.  Read back, each pixel names
  the face (hence the cell) seen there, so a defect's mask is exactly the pixels whose
  cell belongs to that defect, occlusion by the fruit itself or by the cup included.

All lengths are millimetres in the fruit's own frame (the frame of the VTU the dataset
writes: the clean fruit's bounding-box centre at the origin, its axis along z).  The
camera never refits a damaged fruit: its distance is set from the fruit's nominal size,
so a shrunk fruit is smaller in the picture.  :func:`camera_matrices` gives the pinhole
intrinsics and the world-to-camera extrinsics in the OpenCV convention (x right, y down,
z forward; pixel centres at integer coordinates, origin at the top-left pixel).

Masks are stored as COCO run-length encodings (:func:`rle_encode`, column-major,
uncompressed ``counts``), which pycocotools, torchvision and detectron2 read.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import pyvista as pv

STAGES = ("plain", "conveyor", "cup")
#: Vertical field of view range (degrees) and fraction of the picture height the fruit's
#: nominal size spans.
VIEW_ANGLE = (24.0, 40.0)
FILL = (0.45, 0.75)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _random_unit(rng: np.random.Generator) -> np.ndarray:
    return _unit(rng.normal(size=3))


def _perpendicular(v: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    w = _random_unit(rng)
    w = w - (w @ v) * v
    return _unit(w)


def sample_views(rng: np.random.Generator, count: int, size_mm: float, stage: str = "mixed") -> list[dict[str, Any]]:
    """``count`` random views of one fruit of nominal size ``size_mm`` (see the module docstring).

    ``stage``: one of :data:`STAGES`, or ``"mixed"`` (drawn per fruit).  The fruit's pose
    on its stage (which way is up, in the fruit's frame) is drawn once per fruit, the
    camera, lights and colours once per view.  A conveyor fruit lies any way up; a cup
    fruit stands on its stem or blossom end, tilted by up to 30 degrees.
    """
    if stage == "mixed":
        stage = str(rng.choice(STAGES))
    if stage == "cup":
        axis = np.array([0.0, 0.0, 1.0 if rng.random() < 0.5 else -1.0])
        tilt = math.radians(float(rng.uniform(0, 30)))
        up = _unit(math.cos(tilt) * axis + math.sin(tilt) * _perpendicular(axis, rng))
    else:
        up = _random_unit(rng)
    belt = [float(c) for c in rng.uniform([0.08, 0.08, 0.08], [0.35, 0.35, 0.35])]
    cup = [float(c) for c in rng.uniform([0.1, 0.1, 0.1], [0.9, 0.9, 0.9])]
    views = []
    for _ in range(int(count)):
        if stage == "plain":
            look = _random_unit(rng)
        else:  # from above the support plane, 15..85 degrees of elevation
            elevation = math.radians(float(rng.uniform(15, 85)))
            side = _perpendicular(up, rng)
            look = math.sin(elevation) * up + math.cos(elevation) * side
        angle = float(rng.uniform(*VIEW_ANGLE))
        fill = float(rng.uniform(*FILL))
        distance = size_mm / fill / (2 * math.tan(math.radians(angle) / 2))
        target = rng.uniform(-0.06, 0.06, 3) * size_mm
        roll = math.radians(float(rng.uniform(-12, 12)))
        cam_up = up - (up @ look) * look
        if np.linalg.norm(cam_up) < 1e-6:
            cam_up = _perpendicular(look, rng)
        cam_up = _unit(cam_up)
        cam_up = math.cos(roll) * cam_up + math.sin(roll) * np.cross(look, cam_up)
        key = _unit(look + rng.uniform(-0.9, 0.9, 3) + 0.6 * up)
        views.append(
            {
                "stage": stage,
                "up": [float(x) for x in up],
                "eye": [float(x) for x in target + distance * look],
                "target": [float(x) for x in target],
                "view_up": [float(x) for x in cam_up],
                "view_angle_deg": angle,
                "key_light": {"direction": [float(x) for x in key], "intensity": float(rng.uniform(0.7, 1.1))},
                "fill_light": float(rng.uniform(0.15, 0.4)),
                "light_tint": [float(c) for c in rng.uniform([0.9, 0.9, 0.85], [1.0, 1.0, 1.0])],
                "ambient": float(rng.uniform(0.12, 0.25)),
                "gloss": float(rng.uniform(0.1, 0.5)),
                "background": [float(c) for c in rng.uniform(0.2, 0.95, 3)],
                "belt": belt,
                "cup": cup,
            }
        )
    return views


def camera_matrices(view: Mapping[str, Any], size: Sequence[int]) -> dict[str, Any]:
    """Pinhole camera of a view for a ``size = (width, height)`` picture, OpenCV convention.

    ``K`` (3x3 intrinsics, pixels), ``R`` (3x3) and ``t`` (mm) with
    ``x_camera = R @ x_world + t``; a world point projects to ``K @ x_camera`` divided by
    its last coordinate.  Also ``width``, ``height``, ``fov_y_deg``, and
    ``mm_per_pixel_at_target`` (the picture's physical scale at the target's depth).
    """
    width, height = int(size[0]), int(size[1])
    eye, target = np.asarray(view["eye"], float), np.asarray(view["target"], float)
    forward = _unit(target - eye)
    right = _unit(np.cross(forward, np.asarray(view["view_up"], float)))
    down = np.cross(forward, right)
    rot = np.vstack([right, down, forward])
    f = (height / 2) / math.tan(math.radians(view["view_angle_deg"]) / 2)
    k = np.array([[f, 0.0, width / 2 - 0.5], [0.0, f, height / 2 - 0.5], [0.0, 0.0, 1.0]])
    return {
        "width": width,
        "height": height,
        "fov_y_deg": float(view["view_angle_deg"]),
        "K": k.tolist(),
        "R": rot.tolist(),
        "t": (-rot @ eye).tolist(),
        "mm_per_pixel_at_target": float(np.linalg.norm(target - eye) / f),
    }


def project(points: np.ndarray, camera: Mapping[str, Any]) -> np.ndarray:
    """Pixel coordinates ``(n, 2)`` of world points (mm) seen by ``camera`` (:func:`camera_matrices`)."""
    cam = np.asarray(points, float) @ np.asarray(camera["R"]).T + np.asarray(camera["t"])
    uvw = cam @ np.asarray(camera["K"]).T
    return uvw[:, :2] / uvw[:, 2:3]


def stage_meshes(view: Mapping[str, Any], fruit_points: np.ndarray, size_mm: float) -> list[tuple[pv.PolyData, list[float]]]:
    """The stage under the fruit: ``[(mesh, rgb)]`` (a belt for ``conveyor`` and ``cup``, a cup)."""
    import pyvista as pv

    if view["stage"] == "plain":
        return []
    up = np.asarray(view["up"], float)
    low = float((fruit_points @ up).min())
    belt = pv.Plane(center=tuple(up * (low - 0.002 * size_mm)), direction=tuple(up), i_size=8 * size_mm, j_size=8 * size_mm)
    out = [(belt, list(view["belt"]))]
    if view["stage"] == "cup":  # a cone round the fruit's lower part, wider than it at its rim
        rim = 0.22 * size_mm
        height = fruit_points @ up
        ring = fruit_points[np.abs(height - (low + rim)) < 0.04 * size_mm]
        axis_point = ring.mean(axis=0) if len(ring) else up * (low + rim)
        across = ring - axis_point - np.outer((ring - axis_point) @ up, up)
        radius = 1.12 * (float(np.linalg.norm(across, axis=1).max()) if len(ring) else 0.35 * size_mm)
        apex = axis_point - up * (axis_point @ up - low + 0.6 * rim)
        depth = 1.6 * rim
        cup = pv.Cone(
            center=tuple(apex + up * depth / 2),
            direction=tuple(-up),
            height=depth,
            radius=radius,
            capping=False,
            resolution=48,
        )
        out.append((cup, list(view["cup"])))
    return out


class ViewRenderer:
    """One off-screen plotter for every view a process renders (see the module docstring).

    :meth:`set_fruit` adds a fruit's actors once (the damaged fruit shaded and in ids, the
    clean fruit shaded, the stage); :meth:`picture` and :meth:`face_ids` then only switch
    actors, lights and camera per view, which is most of the cost saved (pyvista's
    ``add_mesh`` costs more than a render).
    """

    def __init__(self, size: Sequence[int]) -> None:
        from ramure.app.render import headless_setup

        headless_setup()
        import pyvista as pv

        self.size = (int(size[0]), int(size[1]))
        self.plotter = pv.Plotter(off_screen=True, window_size=list(self.size))
        self.plotter.disable_anti_aliasing()
        self.actors: dict[str, Any] = {}
        self.stage: list[tuple[Any, Any]] = []

    def close(self) -> None:
        """Release the GL context."""
        self.plotter.close()

    def set_fruit(
        self, surface: pv.PolyData, rgb: np.ndarray, clean: pv.PolyData, clean_rgb: np.ndarray, stage: Sequence
    ) -> None:
        """The fruit (damaged and clean surfaces with their face colours) and its stage meshes."""
        p = self.plotter
        p.clear_actors()
        self.actors = {}
        for name, mesh, colours in (("damaged", surface, rgb), ("clean", clean, clean_rgb)):
            shown = mesh.copy(deep=False)
            shown.cell_data["rgb"] = colours
            self.actors[name] = p.add_mesh(
                shown,
                scalars="rgb",
                rgb=True,
                smooth_shading=True,
                split_sharp_edges=mesh.point_data.active_normals is None,  # round marks bring their own
                feature_angle=50.0,
                diffuse=0.85,
                specular_power=30.0,
                render=False,
            )
        code = np.arange(1, surface.n_cells + 1, dtype=np.int64)
        ids = surface.copy(deep=False)
        ids.cell_data["id_rgb"] = np.stack([(code >> 16) & 255, (code >> 8) & 255, code & 255], axis=1).astype(np.uint8)
        self.actors["ids"] = p.add_mesh(ids, scalars="id_rgb", rgb=True, lighting=False, render=False)
        self.stage = []
        for mesh, colour in stage:
            shade = p.add_mesh(mesh, color=tuple(colour), ambient=0.3, diffuse=0.7, render=False)
            flat = p.add_mesh(mesh, color=(0.0, 0.0, 0.0), lighting=False, render=False)
            self.stage.append((shade, flat))

    def _show(self, which: str) -> None:
        for name, actor in self.actors.items():
            actor.SetVisibility(name == which)
        for shade, flat in self.stage:
            shade.SetVisibility(which != "ids")
            flat.SetVisibility(which == "ids")

    def _camera(self, view: Mapping[str, Any]) -> None:
        cam = self.plotter.camera
        cam.position, cam.focal_point, cam.up = tuple(view["eye"]), tuple(view["target"]), tuple(view["view_up"])
        cam.view_angle = float(view["view_angle_deg"])
        distance = float(np.linalg.norm(np.subtract(view["eye"], view["target"])))
        cam.clipping_range = (max(distance * 0.02, 1e-3), distance * 10)

    def _grab(self) -> np.ndarray:
        self.plotter.render()
        return np.asarray(self.plotter.screenshot(None, return_img=True))[..., :3].copy()

    def picture(self, view: Mapping[str, Any], clean: bool = False) -> np.ndarray:
        """The shaded picture of a view of the damaged (or clean) fruit, ``(height, width, 3)`` uint8."""
        import pyvista as pv

        p = self.plotter
        which = "clean" if clean else "damaged"
        self._show(which)
        prop = self.actors[which].prop
        prop.ambient, prop.specular = view["ambient"], view["gloss"]
        p.remove_all_lights()
        p.set_background(tuple(view["background"]))  # type: ignore[arg-type]  # pyvista stubs: decorated method
        target = np.asarray(view["target"], float)
        key = view["key_light"]
        p.add_light(
            pv.Light(
                position=tuple(target + np.asarray(key["direction"]) * 1000.0),
                focal_point=tuple(target),
                color=tuple(view["light_tint"]),
                intensity=key["intensity"],
                light_type="scene light",
            )
        )
        p.add_light(pv.Light(light_type="headlight", intensity=view["fill_light"]))
        self._camera(view)
        return self._grab()

    def face_ids(self, view: Mapping[str, Any]) -> np.ndarray:
        """Per pixel, the index of the damaged surface's face seen there, -1 for the stage or backdrop."""
        self._show("ids")
        self.plotter.set_background((0.0, 0.0, 0.0))  # type: ignore[arg-type]  # pyvista stubs: decorated method
        self._camera(view)
        img = self._grab().astype(np.int64)
        return (img[..., 0] << 16 | img[..., 1] << 8 | img[..., 2]) - 1


def rle_encode(mask: np.ndarray) -> dict[str, Any]:
    """COCO uncompressed RLE of a boolean ``(height, width)`` mask: column-major run lengths,
    starting with a run of zeros (possibly empty)."""
    flat = np.asarray(mask, bool).ravel(order="F")
    change = np.flatnonzero(flat[1:] != flat[:-1]) + 1
    bounds = np.r_[0, change, flat.size]
    runs = np.diff(bounds).tolist()
    if flat.size and flat[0]:
        runs = [0, *runs]
    return {"size": [int(mask.shape[0]), int(mask.shape[1])], "counts": [int(r) for r in runs]}


def rle_decode(rle: Mapping[str, Any]) -> np.ndarray:
    """The boolean mask of an uncompressed COCO RLE (inverse of :func:`rle_encode`)."""
    h, w = (int(x) for x in rle["size"])
    counts = np.asarray(rle["counts"], np.int64)
    values = np.arange(len(counts)) % 2 == 1
    return np.repeat(values, counts).reshape((h, w), order="F")


def bbox(mask: np.ndarray) -> list[int]:
    """COCO ``[x, y, width, height]`` of a mask's pixels (pixel edges; ``[0, 0, 0, 0]`` if empty)."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if rows.size == 0:
        return [0, 0, 0, 0]
    return [int(cols[0]), int(rows[0]), int(cols[-1] - cols[0] + 1), int(rows[-1] - rows[0] + 1)]


def polygons(mask: np.ndarray) -> list[list[float]]:
    """COCO polygons (``[x0, y0, x1, y1, ...]``, pixel-edge coordinates) of a mask's outer
    boundaries, one per connected piece (8-connected pieces touching at a corner split there).

    Traced along pixel edges, so rasterising them gives the mask back, except its holes
    (COCO polygons have none; the RLE is exact).  Straight runs are one segment.
    """
    m = np.pad(np.asarray(mask, bool), 1)
    edges: dict[tuple[int, int], list[tuple[int, int]]] = {}
    # clockwise on screen (y down) round every foreground pixel; coordinates of the unpadded mask
    for dr, dc, start, end in ((-1, 0, (0, 0), (1, 0)), (0, 1, (1, 0), (1, 1)), (1, 0, (1, 1), (0, 1)), (0, -1, (0, 1), (0, 0))):
        rows, cols = np.nonzero(m[1:-1, 1:-1] & ~m[1 + dr : m.shape[0] - 1 + dr, 1 + dc : m.shape[1] - 1 + dc])
        for r, c in zip(rows.tolist(), cols.tolist()):
            edges.setdefault((c + start[0], r + start[1]), []).append((c + end[0], r + end[1]))
    out = []
    while edges:
        first = next(iter(edges))
        loop, point, heading = [first], first, None
        while True:
            options = edges[point]
            nxt = options.pop(_rightmost(options, point, heading) if len(options) > 1 else 0)
            if not options:
                del edges[point]
            heading = (nxt[0] - point[0], nxt[1] - point[1])
            point = nxt
            if point == first and (point not in edges):
                break
            loop.append(point)
            if point == first:
                break
        corners = _corners(loop)
        xs, ys = np.array([p[0] for p in corners], float), np.array([p[1] for p in corners], float)
        if len(corners) >= 3 and float(np.dot(xs, np.roll(ys, -1)) - np.dot(np.roll(xs, -1), ys)) > 0:  # outer, not a hole
            out.append([float(v) for p in corners for v in p])
    return out


def _rightmost(options, point, heading):
    """At a corner two pieces share, the edge turning right of ``heading`` (keeps pieces apart)."""
    if heading is None:
        return 0
    right = (-heading[1], heading[0])  # a right turn on screen (y down)
    for i, o in enumerate(options):
        if (o[0] - point[0], o[1] - point[1]) == right:
            return i
    return 0


def _corners(loop):
    """The loop's points where its direction changes."""
    n = len(loop)
    keep = []
    for i in range(n):
        a, b, c = loop[i - 1], loop[i], loop[(i + 1) % n]
        if (b[0] - a[0]) * (c[1] - b[1]) != (b[1] - a[1]) * (c[0] - b[0]):
            keep.append(b)
    return keep
