"""Exporting the plant as the window shows it: bark, leaves and fruit (volumetric when shown).

OBJ gets what modelling tools expect: one group and one material per part
(``bark``, ``leaves``, ``fruit``) in a ``.mtl`` file beside it, vertex
normals (smooth, per point), and an optional Y-up axis swap (Blender, Unity
and glTF viewers take Y as up; Ramure's turtle grows along Z).  Other
formats (.vtp, .ply, .stl, .gltf) get one merged mesh.  Every file goes
through a temporary file in the same folder, then a rename.
"""
from __future__ import annotations

import io
import pathlib

import numpy as np

from ramure.app.render import BARK, FRUIT, LEAF
from ramure.errors import ValueRefused
from ramure.io import save_mesh, write_text

PART_COLORS = {"bark": BARK, "leaves": LEAF, "fruit": FRUIT}


def plant_parts(mesh, fruit_surface=None):
    """``[(name, polydata)]``: bark, leaves and fruit cells of ``mesh``; the fruit are
    ``fruit_surface`` (the volumes' boundary) when given, else the mesh's spheres."""
    kind = np.asarray(mesh.cell_data["kind"])
    parts = []
    for code, (name, cells) in enumerate((("bark", kind == 0), ("leaves", kind == 1), ("fruit", kind >= 2))):
        if name == "fruit" and fruit_surface is not None and fruit_surface.n_cells:
            part = fruit_surface.extract_surface(algorithm="dataset_surface")
        elif cells.any():
            part = mesh.extract_cells(np.flatnonzero(cells)).extract_surface(algorithm="dataset_surface")
        else:
            continue
        part.clear_data()
        part.cell_data["kind"] = np.full(part.n_cells, code)
        parts.append((name, part))
    return parts


def y_up(points):
    """Z-up to Y-up: (x, y, z) -> (x, z, -y), a rotation (handedness kept)."""
    p = np.asarray(points, float)
    return np.c_[p[:, 0], p[:, 2], -p[:, 1]]


def write_obj(parts, path, yup=False):
    """Wavefront OBJ with groups, materials (``path.mtl``) and vertex normals; returns the path."""
    path = pathlib.Path(path)
    mtl = path.with_suffix(".mtl")
    out = io.StringIO()
    out.write(f"# Ramure plant{' (Y up)' if yup else ' (Z up)'}\nmtllib {mtl.name}\n")
    offset = 0
    for name, part in parts:
        tri = part.triangulate()
        normals = tri.compute_normals(cell_normals=False, point_normals=True, split_vertices=False,
                                      consistent_normals=False, auto_orient_normals=False)
        points = np.asarray(normals.points, float)
        vn = np.asarray(normals.point_data["Normals"], float)
        if yup:
            points, vn = y_up(points), y_up(vn)
        faces = np.asarray(normals.faces).reshape(-1, 4)[:, 1:] + 1 + offset
        out.write(f"g {name}\nusemtl {name}\n")
        np.savetxt(out, points, fmt="v %.6g %.6g %.6g")
        np.savetxt(out, vn, fmt="vn %.4f %.4f %.4f")
        np.savetxt(out, np.repeat(faces, 2, axis=1), fmt="f %d//%d %d//%d %d//%d")
        offset += len(points)
    materials = "".join(f"newmtl {name}\nKd {c[0]:.3f} {c[1]:.3f} {c[2]:.3f}\nKa 0 0 0\nKs 0.05 0.05 0.05\n"
                        f"Ns 10\nd 1\nillum 2\n\n" for name, c in PART_COLORS.items())
    write_text(mtl, materials)
    write_text(path, out.getvalue())
    return path


def export_plant(mesh, path, fruit_surface=None, yup=False):
    """Write the plant (with volumetric fruit when given) by suffix: .obj, .vtp, .vtk, .ply, .stl,
    .gltf/.glb; returns the path."""
    import pyvista as pv

    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    parts = plant_parts(mesh, fruit_surface)
    if suffix == ".obj":
        return write_obj(parts, path, yup)
    if suffix not in (".vtp", ".vtk", ".ply", ".stl", ".gltf", ".glb"):
        raise ValueRefused(f"cannot export to '{suffix}': use .obj, .vtp, .gltf, .ply or .stl")
    merged = pv.merge([p for _, p in parts]) if len(parts) > 1 else parts[0][1]
    if yup:
        merged = merged.copy()
        merged.points = y_up(merged.points)
    if suffix in (".gltf", ".glb"):  # VTK's exporter writes its own files (a .bin beside a .gltf)
        from ramure.app.render import export_gltf

        return pathlib.Path(export_gltf(merged, path))
    return save_mesh(merged, path)
