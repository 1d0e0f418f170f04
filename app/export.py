"""Every 3D export of Ramure: glTF (binary ``.glb`` and JSON ``.gltf``), OBJ + MTL, VTK, PLY, STL.

One front door, :func:`export_mesh`, is used by the CLI (``ramure export``),
the desktop's File > Export, the Jupyter explorer and ``ramure wood -o``.
The mesh is first cut into :class:`Part` s — one per (organ kind, material) —
each a triangle list with its own vertices and smooth vertex normals, built
with numpy; the writers only lay those arrays out:

``.glb``   binary glTF 2.0: a 12-byte header (magic ``glTF``, version 2,
           length), a JSON chunk (padded with spaces) and a BIN chunk (padded
           with zeros), both 4-byte aligned; one mesh with one primitive per
           part, each with POSITION (min/max), NORMAL, indices (uint16 when
           the part has < 65,536 vertices, else uint32) and the
           application attribute ``_LEAF_ID`` (float32: the history leaf
           that made each vertex, so a tool can map a triangle back to the
           derivation); one PBR material per material name, its
           ``baseColorFactor`` the sRGB colour turned linear, double-sided
           (leaves and petals are one polygon thick).
``.gltf``  the same document as JSON, the buffer embedded as a base64 data URI
           (one self-contained file: nothing is written beside it).
``.obj``   one group per organ kind (``g bark``, ``g leaves``...), ``usemtl``
           per material, ``v``/``vn``/``f a//a`` lines; the materials go to
           ``NAME.XXXXXXXX.mtl`` beside it (``Kd`` the colour; ``XXXXXXXX``
           the first 8 hex digits of the materials' SHA-256).  Both files are
           written atomically, the ``.mtl`` first under its new name, so at
           every moment, a crash included, the OBJ on disk names a material
           file that is there and holds its materials; material files of
           earlier exports of NAME (that pattern) go once the OBJ is in place.
``.vtp``/``.vtk``  the mesh as it is (quads stay quads), with cell data
           ``leaf_id``, ``kind`` (organ kind), ``material`` (index into the
           material table, -1 for the default colour of the kind) and ``rgb``.
``.ply``           triangles with per-vertex normals and colours (binary, :func:`ply_bytes`).
``.stl``           the same mesh through VTK (geometry only).

Choices the issue leaves open: the glTF writer is hand-written (about 120
lines of numpy and ``struct``) rather than pygltflib or trimesh — glTF's
binary layout is small and fixed, a dependency would add an install step for
no capability we use, and writing the arrays directly is fast (a 100k-segment
plant writes in well under a second).  Colours: the kind's default (bark,
leaf, fruit, as on screen) unless the cell has a ``material`` index found in
the material table (``materials=`` or the mesh's ``field_data``, see
:func:`material_table`).  ``yup=True`` turns Ramure's Z-up into the Y-up that
glTF, Blender and Unity expect (a rotation, handedness kept).

>>> import pathlib, tempfile, pyvista as pv
>>> out = export_mesh(pv.Cube().triangulate(), pathlib.Path(tempfile.mkdtemp()) / "cube.glb")
>>> out.read_bytes()[:4], read_glb(out)[0]["asset"]["version"]
(b'glTF', '2.0')
"""

from __future__ import annotations

import base64
import glob
import hashlib
import io
import json
import os
import pathlib
import re
import struct
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ramure.app.render import BARK, FRUIT, LEAF
from ramure.errors import RamureError, ValueRefused
from ramure.io import save_mesh, write_bytes, write_text

if TYPE_CHECKING:
    import pyvista as pv

#: The file suffixes :func:`export_mesh` writes.
EXPORT_SUFFIXES = (".glb", ".gltf", ".obj", ".vtp", ".vtk", ".ply", ".stl")

#: Organ kind codes (``kind`` cell data) -> group name and default colour.
KIND_NAMES = {0: "bark", 1: "leaves", 2: "fruit", 3: "organs"}
KIND_COLORS = {0: BARK, 1: LEAF, 2: FRUIT, 3: FRUIT}

_GLB_MAGIC, _JSON_CHUNK, _BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942
_FLOAT, _USHORT, _UINT = 5126, 5123, 5125
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963


@dataclass
class Part:
    """Triangles of one organ kind and one material, with their own vertices.

    ``points`` (n,3) and ``normals`` (n,3) float, ``triangles`` (m,3) int
    indices into ``points``; ``cell_data`` holds per-triangle arrays
    (``leaf_id``, ``kind``, ``material``) when the source mesh had them.
    """

    group: str
    material: str
    color: tuple
    points: np.ndarray
    triangles: np.ndarray
    normals: np.ndarray | None = None
    cell_data: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.color = rgba(self.color)
        if self.normals is None:
            self.normals = point_normals(self.points, self.triangles)


# -- building the parts --------------------------------------------------------


def point_normals(points: ArrayLike, triangles: ArrayLike) -> np.ndarray:
    """Unit vertex normals: the area-weighted sum of the adjacent triangles' normals.

    A vertex with no usable triangle (degenerate, or unused) gets +Z, so every
    normal is unit length (glTF requires it).
    """
    points = np.asarray(points, float)
    tri = np.asarray(triangles, np.int64).reshape(-1, 3)
    n = len(points)
    out = np.zeros((n, 3))
    if len(tri):
        p0, p1, p2 = points[tri[:, 0]], points[tri[:, 1]], points[tri[:, 2]]
        face = np.cross(p1 - p0, p2 - p0)  # length = twice the area
        slots = (tri[:, :, None] * 3 + np.arange(3)).ravel()  # (vertex, component) of each corner
        weights = np.broadcast_to(face[:, None, :], (len(tri), 3, 3)).ravel()
        out[:] = np.bincount(slots, weights=weights, minlength=3 * n).reshape(n, 3)
    length = np.linalg.norm(out, axis=1, keepdims=True)
    bad = length[:, 0] < 1e-20
    out[bad] = (0.0, 0.0, 1.0)
    length[bad] = 1.0
    return out / length


def triangles_of(mesh: pv.DataSet) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(points, triangles, cell)``: the polygons of a pyvista mesh as triangles, with for each
    triangle the index of the cell it came from.

    Meshes of triangles and quads only (a plant's tubes, leaves, polygons) are
    split in numpy, a quad ``abcd`` into ``abc`` and ``acd``; other polygons
    (non-convex ones too) are triangulated by VTK.
    """
    mesh = mesh if hasattr(mesh, "faces") else mesh.extract_surface(algorithm="dataset_surface")
    points = np.asarray(mesh.points, float).reshape(-1, 3)
    fast = _fan_quads(mesh)
    if fast is not None:
        return (points, *fast)
    work = mesh.copy(deep=False)
    work.cell_data["_export_cell"] = np.arange(mesh.n_cells)
    tri = work.triangulate()
    faces = np.asarray(tri.faces)
    if not len(faces):
        return points, np.zeros((0, 3), np.int64), np.zeros(0, np.int64)
    first = tri.n_verts + tri.n_lines  # polygons come after vertices and lines in cell order
    cell = np.asarray(tri.cell_data["_export_cell"])[first : first + len(faces) // 4]
    return np.asarray(tri.points, float), faces.reshape(-1, 4)[:, 1:].astype(np.int64), cell


def _fan_quads(mesh):
    """``(triangles, cell)`` when the mesh has only triangles and quads, else None."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    if mesh.n_verts or mesh.n_lines or mesh.n_strips or not mesh.n_cells:
        return None
    polys = mesh.GetPolys()
    offsets = vtk_to_numpy(polys.GetOffsetsArray()).astype(np.int64)
    conn = vtk_to_numpy(polys.GetConnectivityArray()).astype(np.int64)
    size = np.diff(offsets)
    if size.min() < 3 or size.max() > 4:
        return None
    count = size - 2  # 1 triangle per triangle, 2 per quad
    cell = np.repeat(np.arange(len(size)), count)
    second = np.zeros(len(cell), bool)
    second[np.cumsum(count)[count == 2] - 1] = True  # the quad's second triangle: a c d
    start = offsets[cell]
    corners = np.stack([start, start + 1 + second, start + 2 + second], axis=1)
    return conn[corners], cell


def srgb_to_linear(rgb: ArrayLike) -> np.ndarray:
    """sRGB components in 0..1 to linear light (glTF's ``baseColorFactor`` is linear)."""
    c = np.asarray(rgb, float)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def y_up(points: ArrayLike) -> np.ndarray:
    """Z-up to Y-up: (x, y, z) -> (x, z, -y), a rotation (handedness kept)."""
    p = np.asarray(points, float).reshape(-1, 3)
    return np.c_[p[:, 0], p[:, 2], -p[:, 1]]


def rgba(color: Iterable[float]) -> tuple:
    """``(r, g, b)`` or ``(r, g, b, a)`` (0..1) as four floats, alpha 1 by default."""
    c = [float(v) for v in color]
    return tuple(c[:4] if len(c) >= 4 else c[:3] + [1.0])


def material_table(mesh: pv.DataSet, materials: Mapping[int, Sequence[float]] | None = None) -> dict:
    """``{index: (r, g, b, a)}`` (components 0..1): ``materials`` if given (values RGB or
    RGBA), else the mesh's ``field_data["material_rgba"]`` rows ``(index, r, g, b, a)`` (as
    the grammar's ``#material i r g b [a]`` table is carried), else empty."""
    if materials is not None:
        return {int(i): rgba(c) for i, c in dict(materials).items()}
    data = getattr(mesh, "field_data", {})
    rows = np.atleast_2d(np.asarray(data["material_rgba"], float)) if "material_rgba" in data else ()
    return {int(r[0]): rgba(r[1:]) for r in rows}


def _sub_part(points, tri, cell_data, group, material, color):
    """The triangles ``tri`` of ``points`` as a part with only the vertices they use."""
    used = np.zeros(len(points), bool)
    used[tri.ravel()] = True
    index = np.cumsum(used) - 1  # old vertex -> new (linear, no sort)
    return Part(group, material, color, points[used], index[tri], cell_data=cell_data)


def plant_parts(
    mesh: pv.PolyData,
    fruit_surface: pv.PolyData | None = None,
    materials: Mapping[int, Sequence[float]] | None = None,
    yup: bool = False,
) -> list[Part]:
    """The parts of a plant mesh (cell data ``kind``, optional ``leaf_id`` and ``material``).

    Groups follow the organ kind; within a kind, cells whose ``material`` is in
    the table get that material (``material<i>``), the others the kind's
    default (``bark``, ``leaves``, ``fruit``).  With ``fruit_surface`` (the
    volumetric fruit's boundary) the mesh's fruit spheres are replaced by it.
    """
    points, tri, cell = triangles_of(mesh)
    if yup:
        points = y_up(points)
    n = mesh.n_cells
    kind = _cell_array(mesh, "kind", np.zeros(n, np.int64))[cell]
    leaf = _cell_array(mesh, "leaf_id", np.full(n, -1))[cell]
    material = _cell_array(mesh, "material", np.full(n, -1))[cell]
    table = material_table(mesh, materials)
    if fruit_surface is not None and fruit_surface.n_cells:
        keep = kind < 2
        tri, kind, leaf, material = tri[keep], kind[keep], leaf[keep], material[keep]
    known = np.isin(material, np.fromiter(table, np.int64, len(table)))
    material = np.where(known, material, -1)
    parts = []
    for k in np.unique(kind):
        for m in np.unique(material[kind == k]):
            sel = (kind == k) & (material == m)
            name = f"material{m}" if m >= 0 else KIND_NAMES.get(int(k), f"kind{k}")
            color = table[int(m)] if m >= 0 else KIND_COLORS.get(int(k), FRUIT)
            data = {"leaf_id": leaf[sel], "kind": kind[sel], "material": material[sel]}
            parts.append(_sub_part(points, tri[sel], data, KIND_NAMES.get(int(k), f"kind{k}"), name, color))
    if fruit_surface is not None and fruit_surface.n_cells:
        parts.extend(_fruit_parts(fruit_surface, yup))
    return parts


def _fruit_parts(surface, yup):
    """The volumetric fruit's surface: one part per tissue with its species' colour (material
    ``fruit_<tissue>``, e.g. ``fruit_exocarp``), or one ``fruit`` part without tissue data."""
    points, tri, cell = triangles_of(surface)
    points = y_up(points) if yup else points
    if "tissue" not in surface.cell_data:
        m = len(tri)
        data = {"leaf_id": np.full(m, -1), "kind": np.full(m, 2), "material": np.full(m, -1)}
        return [Part("fruit", "fruit", FRUIT, points, tri, cell_data=data)]
    from ramure.gmap.kernel.storage import TISSUES
    from ramure.gmap.organs.species import hex_rgb, palette

    fd = surface.field_data
    species = str(fd["species"][0]) if "species" in fd else "tomato"
    colours = palette(species, str(fd["ripeness"][0]) if "ripeness" in fd else None)
    tissue = np.asarray(surface.cell_data["tissue"]).astype(np.int64)[cell]
    leaf = _cell_array(surface, "leaf_id", np.full(surface.n_cells, -1))[cell]
    parts = []
    for code in np.unique(tissue):
        sel = tissue == code
        name = TISSUES[int(code)]
        data = {"leaf_id": leaf[sel], "kind": np.full(int(sel.sum()), 2), "material": np.full(int(sel.sum()), -1)}
        colour = tuple(c / 255.0 for c in hex_rgb(colours[name]))
        parts.append(_sub_part(points, tri[sel], data, "fruit", f"fruit_{name}", colour))
    return parts


def color_parts(mesh: pv.DataSet, rgb: ArrayLike | None = None, yup: bool = False, flat: bool = True) -> list[Part]:
    """One part per distinct cell colour (``rgb`` uint8 per cell, default the ``rgb`` cell data):
    for meshes with few colours, such as wood (tissue by season).  ``flat`` gives each triangle
    its own vertices, so shading shows the cells' facets."""
    surface = mesh if hasattr(mesh, "faces") else mesh.extract_surface(algorithm="dataset_surface")
    points, tri, cell = triangles_of(surface)
    points = y_up(points) if yup else points
    colors = np.asarray(surface.cell_data["rgb"] if rgb is None else rgb).reshape(-1, 3)[cell]
    unique, which = np.unique(colors, axis=0, return_inverse=True)
    parts = []
    for i, color in enumerate(unique):
        sel = tri[which.ravel() == i]
        name = "color_" + "".join(f"{int(c):02x}" for c in color)
        if flat:
            pts = points[sel].reshape(-1, 3)
            parts.append(Part(name, name, tuple(color / 255.0), pts, np.arange(len(pts)).reshape(-1, 3)))
        else:
            parts.append(_sub_part(points, sel, {}, name, name, color / 255.0))
    return parts


def _cell_array(mesh, name, default):
    return np.asarray(mesh.cell_data[name]).astype(np.int64) if name in mesh.cell_data else default


# -- glTF ------------------------------------------------------------------------


def gltf_document(parts: Sequence[Part]) -> tuple[dict, bytes]:
    """The glTF 2.0 JSON document (without ``buffers[0].uri``) and its binary buffer."""
    parts = [p for p in parts if len(p.triangles)]
    if not parts:
        raise ValueRefused("nothing to export: the mesh has no surface")
    names = list(dict.fromkeys(p.material for p in parts))
    colors = {p.material: p.color for p in parts}
    doc: dict[str, Any] = {
        "asset": {"version": "2.0", "generator": "Ramure"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "plant"}],
        "materials": [_material(name, colors[name]) for name in names],
        "meshes": [{"name": "plant", "primitives": []}],
        "accessors": [],
        "bufferViews": [],
    }
    blob = io.BytesIO()
    for part in parts:
        attributes = {
            "POSITION": _accessor(doc, blob, part.points, "VEC3", _ARRAY_BUFFER, bounds=True),
            "NORMAL": _accessor(doc, blob, part.normals, "VEC3", _ARRAY_BUFFER),
        }
        if "leaf_id" in part.cell_data:
            attributes["_LEAF_ID"] = _accessor(doc, blob, _vertex_leaf(part), "SCALAR", _ARRAY_BUFFER)
        indices = part.triangles.astype(np.uint16 if len(part.points) < 65536 else np.uint32)
        primitive = {
            "attributes": attributes,
            "mode": 4,
            "material": names.index(part.material),
            "indices": _accessor(doc, blob, indices.ravel(), "SCALAR", _ELEMENT_ARRAY_BUFFER),
            "extras": {"group": part.group},
        }
        doc["meshes"][0]["primitives"].append(primitive)
    data = blob.getvalue()
    doc["buffers"] = [{"byteLength": len(data)}]
    return doc, data


def _material(name, color):
    r, g, b = srgb_to_linear(color[:3]).round(6).tolist()
    out = {
        "name": name,
        "doubleSided": True,
        "pbrMetallicRoughness": {
            "baseColorFactor": [r, g, b, round(color[3], 6)],
            "metallicFactor": 0.0,
            "roughnessFactor": 0.85,
        },
    }
    if color[3] < 1.0:
        out["alphaMode"] = "BLEND"
    return out


def _vertex_leaf(part):
    """Per-vertex leaf id (float32, exact below 2**24): the id of a triangle using the vertex."""
    leaf = np.full(len(part.points), -1.0)
    leaf[part.triangles.ravel()] = np.repeat(part.cell_data["leaf_id"], 3)
    return leaf


def _accessor(doc, blob, array, kind, target, bounds: bool = False):
    """Append ``array`` to the buffer (4-byte aligned) with a buffer view and an accessor."""
    array = np.ascontiguousarray(array, np.float32 if array.dtype.kind == "f" else array.dtype)
    component = {np.dtype(np.float32): _FLOAT, np.dtype(np.uint16): _USHORT, np.dtype(np.uint32): _UINT}[array.dtype]
    offset = blob.tell()
    blob.write(array.tobytes())
    blob.write(b"\0" * (-blob.tell() % 4))
    doc["bufferViews"].append({"buffer": 0, "byteOffset": offset, "byteLength": array.nbytes, "target": target})
    accessor = {"bufferView": len(doc["bufferViews"]) - 1, "componentType": component, "count": len(array), "type": kind}
    if bounds:
        accessor["min"] = array.min(axis=0).tolist()
        accessor["max"] = array.max(axis=0).tolist()
    doc["accessors"].append(accessor)
    return len(doc["accessors"]) - 1


def glb_bytes(parts: Sequence[Part]) -> bytes:
    """A binary glTF (``.glb``) of the parts."""
    doc, data = gltf_document(parts)
    text = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 4)
    data += b"\0" * (-len(data) % 4)
    total = 12 + 8 + len(text) + 8 + len(data)
    return b"".join(
        [
            struct.pack("<III", _GLB_MAGIC, 2, total),
            struct.pack("<II", len(text), _JSON_CHUNK),
            text,
            struct.pack("<II", len(data), _BIN_CHUNK),
            data,
        ]
    )


def gltf_text(parts: Sequence[Part]) -> str:
    """A self-contained JSON glTF (``.gltf``): the buffer is a base64 data URI."""
    doc, data = gltf_document(parts)
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(data).decode("ascii")
    return json.dumps(doc, separators=(",", ":"))


def read_glb(path: str | os.PathLike) -> tuple[dict, bytes]:
    """``(json document, binary chunk)`` of a ``.glb`` file; a malformed file is a :class:`RamureError`."""
    raw = pathlib.Path(path).read_bytes()
    if len(raw) < 20:
        raise RamureError(f"{path}: not a binary glTF (too short)")
    magic, version, total = struct.unpack_from("<III", raw)
    if magic != _GLB_MAGIC or version != 2 or total != len(raw):
        raise RamureError(f"{path}: not a binary glTF 2.0 (magic, version or length wrong)")
    length, kind = struct.unpack_from("<II", raw, 12)
    if kind != _JSON_CHUNK:
        raise RamureError(f"{path}: the first chunk is not JSON")
    doc = json.loads(raw[20 : 20 + length])
    data = b""
    if 20 + length < total:
        blen, bkind = struct.unpack_from("<II", raw, 20 + length)
        if bkind != _BIN_CHUNK:
            raise RamureError(f"{path}: the second chunk is not BIN")
        data = raw[28 + length : 28 + length + blen]
    return doc, data


def accessor_array(doc: dict, data: bytes, index: int) -> np.ndarray:
    """The numpy array of accessor ``index`` of a glTF document and its binary buffer."""
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    dtype = {_FLOAT: np.float32, _USHORT: np.uint16, _UINT: np.uint32}[acc["componentType"]]
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[acc["type"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    flat = np.frombuffer(data, dtype, acc["count"] * width, start)
    return flat.reshape(-1, width) if width > 1 else flat


# -- OBJ ---------------------------------------------------------------------------


def obj_text(parts: Sequence[Part], mtl_name: str, yup: bool = False) -> str:
    """OBJ text: ``g`` per organ kind, ``usemtl`` per material, ``v``, ``vn`` and ``f a//a``."""
    out = io.StringIO()
    out.write(f"# Ramure plant{' (Y up)' if yup else ' (Z up)'}\nmtllib {mtl_name}\n")
    offset, group = 0, None
    for part in parts:
        if part.group != group:
            out.write(f"g {part.group}\n")
            group = part.group
        out.write(f"usemtl {part.material}\n")
        out.write(_lines("v %.6g %.6g %.6g\n", part.points))
        out.write(_lines("vn %.4f %.4f %.4f\n", part.normals))
        faces = part.triangles + 1 + offset
        out.write(_lines("f %d//%d %d//%d %d//%d\n", np.repeat(faces, 2, axis=1)))
        offset += len(part.points)
    return out.getvalue()


def _lines(fmt, rows, chunk=65536):
    """``fmt`` applied to every row: one ``%`` per chunk of rows (4x faster than ``np.savetxt``)."""
    rows = np.asarray(rows)
    return "".join(
        (fmt * len(block)) % tuple(block.ravel().tolist()) for block in (rows[i : i + chunk] for i in range(0, len(rows), chunk))
    )


def mtl_text(parts: Sequence[Part]) -> str:
    """The ``.mtl`` materials of the parts (``Kd`` the sRGB colour), each once."""
    colors = {p.material: p.color for p in parts}
    return "".join(
        f"newmtl {name}\nKd {c[0]:.4f} {c[1]:.4f} {c[2]:.4f}\nKa 0 0 0\nKs 0.05 0.05 0.05\nNs 10\nd {c[3]:.4g}\nillum 2\n\n"
        for name, c in colors.items()
    )


def write_obj(parts: Sequence[Part], path: str | os.PathLike, yup: bool = False) -> pathlib.Path:
    """Write ``path`` (.obj) and its material file beside it, each atomically, the material file
    first under a name of its own (see the module docstring): a ``kill -9`` between the two
    leaves the previous OBJ with the previous materials, never an OBJ beside a material file
    that lacks its materials."""
    path = pathlib.Path(path)
    parts = [p for p in parts if len(p.triangles)]
    if not parts:
        raise ValueRefused("nothing to export: the mesh has no surface")
    if path.is_dir():
        raise RamureError(f"cannot write {path}: it is a folder")
    materials = mtl_text(parts)
    mtl = material_file(path, materials)
    body = obj_text(parts, mtl.name, yup)
    write_text(mtl, materials)
    write_text(path, body)
    for old in path.parent.glob(f"{glob.escape(path.stem)}.*.mtl"):
        if old != mtl and re.fullmatch(r"[0-9a-f]{8}", old.name[len(path.stem) + 1 : -len(".mtl")]):
            old.unlink(missing_ok=True)  # an earlier export's materials: no OBJ names them now
    return path


def material_file(path: pathlib.Path, materials: str) -> pathlib.Path:
    """The material file of OBJ ``path`` for ``materials``: ``NAME.XXXXXXXX.mtl``, named by the
    content, so new materials never replace the file the OBJ on disk still names.

    >>> material_file(pathlib.Path("out/plant.obj"), "newmtl bark\\n").name
    'plant.0739fd26.mtl'
    """
    digest = hashlib.sha256(materials.encode("utf-8")).hexdigest()[:8]
    return path.with_name(f"{path.stem}.{digest}.mtl")


# -- VTK ---------------------------------------------------------------------------


def vtk_mesh(
    mesh: pv.PolyData,
    fruit_surface: pv.PolyData | None = None,
    materials: Mapping[int, Sequence[float]] | None = None,
    yup: bool = False,
) -> pv.PolyData:
    """The plant mesh for VTK formats: cells as they are, cell data ``leaf_id``, ``kind``,
    ``material`` and ``rgb`` (uint8, the export colour); volumetric fruit replace the spheres."""
    import pyvista as pv

    out = mesh.copy(deep=True)
    n = out.n_cells
    kind = _cell_array(out, "kind", np.zeros(n, np.int64))
    table = material_table(mesh, materials)
    material = _cell_array(out, "material", np.full(n, -1))
    material = np.where(np.isin(material, np.fromiter(table, np.int64, len(table))), material, -1)
    out.cell_data["kind"] = kind.astype(np.int8)
    out.cell_data["leaf_id"] = _cell_array(out, "leaf_id", np.full(n, -1))
    out.cell_data["material"] = material.astype(np.int32)
    out.cell_data["rgb"] = _rgb(kind, material, table)
    if fruit_surface is not None and fruit_surface.n_cells:
        keep = np.flatnonzero(kind < 2)
        out = out.extract_cells(keep).extract_surface(algorithm="dataset_surface")  # type: ignore[arg-type]  # pyvista stubs: int64 indices
        fruit = fruit_surface.extract_surface(algorithm="dataset_surface")
        fruit.clear_data()
        m = fruit.n_cells
        for name, value in (
            ("kind", np.full(m, 2, np.int8)),
            ("leaf_id", np.full(m, -1)),
            ("material", np.full(m, -1, np.int32)),
            ("rgb", np.tile(np.round(np.asarray(FRUIT) * 255).astype(np.uint8), (m, 1))),
        ):
            fruit.cell_data[name] = value
        out = pv.merge([out, fruit], merge_points=False)
        if not isinstance(out, pv.PolyData):
            out = out.extract_surface(algorithm="dataset_surface")
    if yup:
        out.points = y_up(out.points)
    return out


def _rgb(kind, material, table):
    rgb = np.array([KIND_COLORS.get(int(k), FRUIT) for k in range(4)] + [FRUIT])[np.clip(kind, 0, 4)]
    for index, color in table.items():
        rgb[material == index] = color[:3]
    return np.round(rgb * 255).astype(np.uint8)


# -- the front door ---------------------------------------------------------------


def check_suffix(path: str | os.PathLike) -> pathlib.Path:
    """``path`` as a Path if its suffix is one Ramure exports to, else :class:`ValueRefused`."""
    path = pathlib.Path(path)
    if path.suffix.lower() not in EXPORT_SUFFIXES:
        raise ValueRefused(
            f"cannot export to '{path.suffix or path.name}': use {', '.join(EXPORT_SUFFIXES[:-1])} or {EXPORT_SUFFIXES[-1]}"
        )
    return path


def ply_bytes(parts: Sequence[Part]) -> bytes:
    """A binary little-endian PLY file of ``parts``: triangles only, each vertex with its
    normal and its part's colour (``red green blue alpha``, 0..255), so trimesh, MeshLab and
    VTK read the colours."""
    parts = [p for p in parts if len(p.triangles)]
    counts = [len(p.points) for p in parts]
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    vertex = np.dtype([("p", "<f4", 3), ("n", "<f4", 3), ("c", "u1", 4)])
    face = np.dtype([("k", "u1"), ("v", "<i4", 3)])
    vertices = np.zeros(int(offsets[-1]), vertex)
    faces = np.zeros(sum(len(p.triangles) for p in parts), face)
    faces["k"] = 3
    row = 0
    for part, start in zip(parts, offsets[:-1].tolist()):
        block = vertices[start : start + len(part.points)]
        block["p"], block["n"] = part.points, part.normals
        block["c"] = np.round(np.clip(part.color, 0, 1) * 255).astype(np.uint8)
        faces["v"][row : row + len(part.triangles)] = np.asarray(part.triangles) + start
        row += len(part.triangles)
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment written by Ramure\n"
        f"element vertex {len(vertices)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    return header.encode("ascii") + vertices.tobytes() + faces.tobytes()


def export_parts(parts: Sequence[Part], path: str | os.PathLike, yup: bool = False) -> pathlib.Path:
    """Write already built parts as ``.glb``, ``.gltf``, ``.obj`` or ``.ply``."""
    path = check_suffix(path)
    suffix = path.suffix.lower()
    if suffix == ".ply":
        return write_bytes(path, ply_bytes(parts))
    if suffix == ".glb":
        return write_bytes(path, glb_bytes(parts))
    if suffix == ".gltf":
        return write_text(path, gltf_text(parts))
    if suffix == ".obj":
        return write_obj(parts, path, yup)
    raise ValueRefused(f"cannot export parts to '{suffix}': use .glb, .gltf, .obj or .ply")


def export_mesh(
    mesh: pv.PolyData,
    path: str | os.PathLike,
    fruit_surface: pv.PolyData | None = None,
    materials: Mapping[int, Sequence[float]] | None = None,
    yup: bool = False,
) -> pathlib.Path:
    """Write a plant mesh by suffix (see the module docstring); returns the path.

    ``fruit_surface``: the volumetric fruit to write instead of the fruit
    spheres; ``materials``: ``{index: (r, g, b)}`` for the cells' ``material``
    indices (default: the mesh's own table); ``yup``: Y-up axes.
    """
    path = check_suffix(path)
    suffix = path.suffix.lower()
    if suffix in (".glb", ".gltf", ".obj", ".ply"):
        return export_parts(plant_parts(mesh, fruit_surface, materials, yup), path, yup)
    shown = vtk_mesh(mesh, fruit_surface, materials, yup)
    if suffix == ".stl":
        shown = shown.triangulate()
    return save_mesh(shown, path)


def export_colored(mesh: pv.DataSet, path: str | os.PathLike, rgb: ArrayLike | None = None, yup: bool = False) -> pathlib.Path:
    """Write a mesh coloured per cell (``rgb`` cell data, e.g. wood) by suffix; returns the path."""
    path = check_suffix(path)
    if path.suffix.lower() in (".glb", ".gltf", ".obj", ".ply"):
        return export_parts(color_parts(mesh, rgb, yup), path, yup)
    surface = mesh.copy(deep=True)
    if yup:
        surface.points = y_up(surface.points)
    return save_mesh(surface, path)


__all__ = [
    "EXPORT_SUFFIXES",
    "Part",
    "accessor_array",
    "check_suffix",
    "color_parts",
    "export_colored",
    "export_mesh",
    "export_parts",
    "glb_bytes",
    "gltf_document",
    "gltf_text",
    "material_table",
    "mtl_text",
    "obj_text",
    "plant_parts",
    "ply_bytes",
    "point_normals",
    "read_glb",
    "srgb_to_linear",
    "triangles_of",
    "vtk_mesh",
    "write_obj",
    "y_up",
]
