"""Exports (ramure.app.export): binary/JSON glTF, OBJ + MTL, VTK; read back by hand and by VTK."""

from __future__ import annotations

import base64
import json
import os
import pathlib
import struct

import numpy as np
import pytest
import pyvista as pv

from ramure.app import export as E
from ramure.app.render import BARK, LEAF
from ramure.errors import RamureError, ValueRefused
from ramure.lsys import LSystem

FRUIT_TREE = "fruit_tree"


@pytest.fixture(scope="module")
def mesh():
    return LSystem.from_file(FRUIT_TREE).derive(n=4).skeleton().to_polydata(sides=6)


def n_triangles(mesh):
    """Triangles of a mesh of quads and triangles: 2 per quad, 1 per triangle."""
    faces = np.asarray(mesh.faces)
    i, count = 0, 0
    while i < len(faces):
        count += faces[i] - 2
        i += faces[i] + 1
    return count


def blocks(data):
    if isinstance(data, pv.MultiBlock):
        for block in data:
            yield from blocks(block)
    elif data is not None:
        yield data


def test_glb_layout_by_hand(mesh, tmp_path):
    path = E.export_mesh(mesh, tmp_path / "plant.glb")
    raw = path.read_bytes()
    magic, version, total = struct.unpack_from("<III", raw)
    assert raw[:4] == b"glTF" and version == 2 and total == len(raw) == path.stat().st_size
    json_len, json_type = struct.unpack_from("<II", raw, 12)
    assert json_type == 0x4E4F534A and json_len % 4 == 0
    bin_len, bin_type = struct.unpack_from("<II", raw, 20 + json_len)
    assert bin_type == 0x004E4942 and bin_len % 4 == 0 and 28 + json_len + bin_len == total
    doc = json.loads(raw[20 : 20 + json_len])
    assert doc["buffers"][0]["byteLength"] <= bin_len and "uri" not in doc["buffers"][0]
    prims = doc["meshes"][0]["primitives"]
    assert [m["name"] for m in doc["materials"]] == ["bark", "leaves", "fruit"]
    assert len(prims) == 3 and sorted(p["material"] for p in prims) == [0, 1, 2]
    data = raw[28 + json_len :]
    triangles = 0
    for prim in prims:
        pos = E.accessor_array(doc, data, prim["attributes"]["POSITION"])
        nrm = E.accessor_array(doc, data, prim["attributes"]["NORMAL"])
        idx = E.accessor_array(doc, data, prim["indices"])
        acc = doc["accessors"][prim["attributes"]["POSITION"]]
        assert acc["count"] == len(pos) == len(nrm) and np.allclose(acc["min"], pos.min(0))
        assert np.allclose(acc["max"], pos.max(0))
        assert np.allclose(np.linalg.norm(nrm, axis=1), 1, atol=1e-5)
        assert len(idx) % 3 == 0 and idx.max() < len(pos)
        for view in doc["bufferViews"]:
            assert view["byteOffset"] % 4 == 0
        leaf = E.accessor_array(doc, data, prim["attributes"]["_LEAF_ID"])
        assert set(leaf.astype(int).tolist()) <= set(np.asarray(mesh.cell_data["leaf_id"]).tolist())
        triangles += len(idx) // 3
    assert triangles == n_triangles(mesh)
    leaves = doc["materials"][1]["pbrMetallicRoughness"]["baseColorFactor"]
    assert np.allclose(leaves[:3], E.srgb_to_linear(LEAF), atol=1e-6) and leaves[3] == 1.0
    assert doc["materials"][1]["doubleSided"] is True


def test_glb_and_gltf_read_back_by_vtk(mesh, tmp_path):
    for suffix in (".glb", ".gltf"):
        path = E.export_mesh(mesh, tmp_path / f"plant{suffix}")
        parts = list(blocks(pv.read(path)))
        assert sum(p.n_cells for p in parts) == n_triangles(mesh)
        colours = {tuple(np.round(np.ravel(p.field_data["BaseColorMultiplier"])[:3], 5).tolist()) for p in parts}
        assert len(parts) == 3 and len(colours) == 3  # one primitive per material, three materials


def test_gltf_embeds_the_same_buffer_as_glb(mesh, tmp_path):
    glb_doc, glb_bin = E.read_glb(E.export_mesh(mesh, tmp_path / "p.glb"))
    doc = json.loads(E.export_mesh(mesh, tmp_path / "p.gltf").read_text())
    prefix, _, payload = doc["buffers"][0]["uri"].partition(",")
    assert prefix == "data:application/octet-stream;base64"
    assert base64.b64decode(payload) == glb_bin[: glb_doc["buffers"][0]["byteLength"]]
    assert sorted(os.listdir(tmp_path)) == ["p.glb", "p.gltf"]  # nothing written beside either


def test_materials_table_gives_one_primitive_per_material(tmp_path):
    quad = pv.PolyData(
        np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], float),
        faces=[4, 0, 1, 2, 3, 4, 1, 4, 5, 2, 3, 0, 2, 3],
    )
    quad.cell_data["kind"] = np.array([1, 1, 0])
    quad.cell_data["leaf_id"] = np.array([5, 6, 7])
    quad.cell_data["material"] = np.array([3, 9, 3])  # 9 is not in the table: the kind's colour
    doc, data = E.read_glb(E.export_mesh(quad, tmp_path / "m.glb", materials={3: (1.0, 0.5, 0.0)}))
    names = [m["name"] for m in doc["materials"]]
    assert sorted(names) == ["leaves", "material3"]
    by_name = {m["name"]: m["pbrMetallicRoughness"]["baseColorFactor"][:3] for m in doc["materials"]}
    assert np.allclose(by_name["material3"], E.srgb_to_linear((1.0, 0.5, 0.0)))
    groups = [p["extras"]["group"] for p in doc["meshes"][0]["primitives"]]
    assert groups == ["bark", "leaves", "leaves"]  # bark with material 3, leaf with 3, leaf by default
    counts = [doc["accessors"][p["indices"]]["count"] // 3 for p in doc["meshes"][0]["primitives"]]
    assert counts == [1, 2, 2]
    vtp = pv.read(E.export_mesh(quad, tmp_path / "m.vtp", materials={3: (1.0, 0.5, 0.0)}))
    assert vtp.cell_data["material"].tolist() == [3, -1, 3] and vtp.cell_data["leaf_id"].tolist() == [5, 6, 7]
    assert vtp.cell_data["rgb"][0].tolist() == [255, 128, 0]
    assert np.allclose(vtp.cell_data["rgb"][1] / 255, LEAF, atol=0.003)


def test_material_table_from_the_mesh_field_data():
    quad = pv.PolyData(np.eye(3), faces=[3, 0, 1, 2])
    quad.cell_data["material"] = np.array([2])
    quad.field_data["material_rgba"] = np.array([[2, 0.1, 0.2, 0.3, 0.5]])
    assert E.material_table(quad) == {2: (0.1, 0.2, 0.3, 0.5)}
    (part,) = E.plant_parts(quad)
    assert part.material == "material2" and part.color == (0.1, 0.2, 0.3, 0.5)
    (material,) = E.gltf_document([part])[0]["materials"]
    assert material["alphaMode"] == "BLEND" and material["pbrMetallicRoughness"]["baseColorFactor"][3] == 0.5


def test_obj_has_groups_materials_normals(mesh, tmp_path):
    path = E.export_mesh(mesh, tmp_path / "plant.obj")
    lines = path.read_text().splitlines()
    (mtl_path,) = tmp_path.glob("plant.*.mtl")
    mtl = mtl_path.read_text()
    assert f"mtllib {mtl_path.name}" in lines and mtl.count("newmtl") == 3
    assert [ln.split()[1] for ln in lines if ln.startswith("g ")] == ["bark", "leaves", "fruit"]
    assert f"Kd {BARK[0]:.4f} {BARK[1]:.4f} {BARK[2]:.4f}" in mtl
    v = sum(ln.startswith("v ") for ln in lines)
    normals = np.array([[float(x) for x in ln.split()[1:]] for ln in lines if ln.startswith("vn ")])
    assert len(normals) == v and np.allclose(np.linalg.norm(normals, axis=1), 1, atol=1e-3)
    faces = [ln for ln in lines if ln.startswith("f ")]
    assert len(faces) == n_triangles(mesh) and all("//" in f for f in faces)
    assert pv.read(path).n_cells == n_triangles(mesh)


def test_vtk_keeps_cells_and_cell_data(mesh, tmp_path):
    for suffix in (".vtp", ".vtk"):
        back = pv.read(E.export_mesh(mesh, tmp_path / f"plant{suffix}"))
        assert back.n_cells == mesh.n_cells  # quads stay quads
        assert np.array_equal(back.cell_data["leaf_id"], mesh.cell_data["leaf_id"])
        assert np.array_equal(back.cell_data["kind"], mesh.cell_data["kind"])
        assert set(back.cell_data["material"].tolist()) == {-1}
        assert back.cell_data["rgb"].shape == (mesh.n_cells, 3)


def test_y_up_swaps_height_to_y(mesh, tmp_path):
    doc, data = E.read_glb(E.export_mesh(mesh, tmp_path / "y.glb", yup=True))
    lo = np.min([doc["accessors"][p["attributes"]["POSITION"]]["min"] for p in doc["meshes"][0]["primitives"]], 0)
    hi = np.max([doc["accessors"][p["attributes"]["POSITION"]]["max"] for p in doc["meshes"][0]["primitives"]], 0)
    b = np.asarray(mesh.bounds).reshape(3, 2)
    assert np.isclose(hi[1] - lo[1], b[2, 1] - b[2, 0], rtol=1e-5)  # the plant's height is along Y
    assert np.isclose(lo[2], -b[1, 1], rtol=1e-5)


def test_unknown_suffix_is_refused_and_writes_nothing(mesh, tmp_path):
    for name in ("plant.xyz", "plant"):
        with pytest.raises(ValueRefused, match="cannot export to"):
            E.export_mesh(mesh, tmp_path / name)
    assert os.listdir(tmp_path) == []


def test_failed_export_keeps_the_previous_file(tmp_path):
    target = tmp_path / "plant.glb"
    target.write_bytes(b"previous")
    with pytest.raises(ValueRefused, match="nothing to export"):
        E.export_mesh(pv.PolyData(), target)
    assert target.read_bytes() == b"previous" and os.listdir(tmp_path) == ["plant.glb"]
    (tmp_path / "folder.obj").mkdir()
    with pytest.raises(RamureError, match="it is a folder"):
        E.export_mesh(pv.Cube(), tmp_path / "folder.obj")
    assert not list(tmp_path.glob("*.mtl"))  # refused before the material file is written


def test_glb_replaces_atomically(mesh, tmp_path, monkeypatch):
    """A failure while writing leaves the old file whole and no temporary file behind."""
    target = E.export_mesh(mesh, tmp_path / "plant.glb")
    before = target.read_bytes()
    import ramure.io

    def broken_commit(tmp, path):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(ramure.io, "_commit", broken_commit)
    with pytest.raises(RamureError, match="No space left"):
        E.export_mesh(mesh, target, yup=True)
    assert target.read_bytes() == before and os.listdir(tmp_path) == ["plant.glb"]


def test_point_normals_closed_form():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    n = E.point_normals(square, [[0, 1, 2], [0, 2, 3]])
    assert np.allclose(n, [0, 0, 1])
    tent = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 1], [0, -1, 1]], float)  # two faces meeting at an edge
    n = E.point_normals(tent, [[0, 1, 2], [0, 3, 1]])
    assert np.allclose(n[2], np.array([0, -1, 1]) / np.sqrt(2))
    assert np.allclose(n[0], [0, 0, 1])  # the shared edge averages the two faces
    assert np.allclose(E.point_normals(np.zeros((2, 3)), np.zeros((0, 3), int)), [0, 0, 1])  # unused: +Z


def test_non_convex_polygon_is_triangulated_with_its_area():
    ell = pv.PolyData(
        np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]], float), faces=[6, 0, 1, 2, 3, 4, 5]
    )
    points, tri, cell = E.triangles_of(ell)
    area = (
        0.5 * np.linalg.norm(np.cross(points[tri[:, 1]] - points[tri[:, 0]], points[tri[:, 2]] - points[tri[:, 0]]), axis=1).sum()
    )
    assert len(tri) == 4 and np.isclose(area, 3.0) and set(cell.tolist()) == {0}


def test_colored_export_one_material_per_colour(tmp_path):
    cube = pv.Cube().extract_surface(algorithm="dataset_surface")
    cube.cell_data["rgb"] = np.array([[200, 10, 10]] * 3 + [[10, 200, 10]] * 3, np.uint8)
    doc, data = E.read_glb(E.export_colored(cube, tmp_path / "c.glb"))
    assert sorted(m["name"] for m in doc["materials"]) == ["color_0ac80a", "color_c80a0a"]
    for prim in doc["meshes"][0]["primitives"]:
        normals = E.accessor_array(doc, data, prim["attributes"]["NORMAL"])
        assert len(np.unique(np.round(normals, 6), axis=0)) == 3  # flat: three faces, three normals
    assert sum(p.n_cells for p in blocks(pv.read(tmp_path / "c.glb"))) == 12


def test_cli_export(tmp_path, capsys):
    from ramure.app.cli import main

    run = ["export", "fruit_tree", "-n", "3"]
    assert main(run + ["-o", str(tmp_path / "t.glb"), "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["cells"] > 0 and (tmp_path / "t.glb").read_bytes()[:4] == b"glTF"
    assert main(run + ["-o", str(tmp_path / "t.xyz")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "must end with" in err and not (tmp_path / "t.xyz").exists()


def test_render_colours_follow_the_material_table():
    from ramure.app.render import plant_colors

    tri = pv.PolyData(np.eye(3), faces=[3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2])
    tri.cell_data["kind"] = np.array([0, 1, 1])
    tri.cell_data["leaf_id"] = np.array([1, 2, 3])
    tri.cell_data["material"] = np.array([0, 4, 7])  # 7 has no colour: the kind's
    tri.field_data["material_rgb"] = np.array([[4, 1.0, 1.0, 1.0]])
    rgb = plant_colors(tri)
    assert rgb[1].tolist() == [255, 255, 255] and np.allclose(rgb[2] / 255, LEAF, atol=0.005)
    assert np.allclose(rgb[0] / 255, BARK, atol=0.005)
    assert plant_colors(tri, selected=[2])[1].tolist() == [255, 0, 0]  # selection still shows red


def test_wood_export_writes_one_material_per_tissue_colour(tmp_path):
    from ramure.app.commands.wood import export_glb

    grid = pv.ImageData(dimensions=(3, 2, 2)).cast_to_unstructured_grid()  # two hexahedra
    grid.cell_data["rgb"] = np.array([[214, 170, 110], [110, 70, 40]], np.uint8)
    obj = export_glb(grid, tmp_path / "wood.obj")
    (mtl,) = tmp_path.glob("wood.*.mtl")
    assert mtl.read_text().count("newmtl") == 2
    faces = [ln for ln in obj.read_text().splitlines() if ln.startswith("f ")]
    assert len(faces) == 2 * 10  # 10 boundary quads (the shared face is inside), 2 triangles each
    doc, _ = E.read_glb(export_glb(grid, tmp_path / "wood.glb"))
    assert sorted(m["name"] for m in doc["materials"]) == ["color_6e4628", "color_d6aa6e"]


def test_obj_and_materials_change_together(mesh, tmp_path, monkeypatch):
    """Issue 37, item 10: a crash between the two files never leaves an OBJ beside a material
    file that lacks its materials; the next export leaves one material file, no debris."""
    target = tmp_path / "plant.obj"
    E.export_mesh(mesh, target)
    old_obj = target.read_text()
    other = mesh.copy()
    other.field_data["material_rgba"] = np.array([[7, 0.9, 0.1, 0.1, 1.0]])
    other.cell_data["material"] = np.full(other.n_cells, 7)
    written = []

    def killed_at_the_obj(path, text, *args, **kwargs):
        if str(path).endswith(".obj"):
            raise RamureError("killed")  # as a kill -9 right after the material file
        written.append(pathlib.Path(path))
        return real(path, text, *args, **kwargs)

    real = E.write_text
    monkeypatch.setattr(E, "write_text", killed_at_the_obj)
    with pytest.raises(RamureError, match="killed"):
        E.export_mesh(other, target)
    assert target.read_text() == old_obj
    named = tmp_path / next(ln.split()[1] for ln in old_obj.splitlines() if ln.startswith("mtllib"))
    used = {ln.split()[1] for ln in old_obj.splitlines() if ln.startswith("usemtl")}
    assert used <= {ln.split()[1] for ln in named.read_text().splitlines() if ln.startswith("newmtl")}
    assert written and written[0] != named  # the new materials went to a file of their own
    monkeypatch.setattr(E, "write_text", real)
    E.export_mesh(other, target)
    (mtl,) = tmp_path.glob("plant.*.mtl")  # the earlier ones are gone
    assert f"mtllib {mtl.name}" in target.read_text() and "material7" in mtl.read_text()
    (tmp_path / "plant.mtl").write_text("a user's own file")  # not of our pattern: left alone
    E.export_mesh(mesh, target)
    assert (tmp_path / "plant.mtl").read_text() == "a user's own file"


def test_ply_is_triangles_with_the_organs_colours(mesh, tmp_path):
    path = E.export_mesh(mesh, tmp_path / "plant.ply")
    data = path.read_bytes()
    head, body = data.split(b"end_header\n", 1)
    lines = head.decode("ascii").splitlines()
    assert lines[:2] == ["ply", "format binary_little_endian 1.0"]
    n_vertices = int(next(x for x in lines if x.startswith("element vertex")).split()[-1])
    n_faces = int(next(x for x in lines if x.startswith("element face")).split()[-1])
    assert n_faces == n_triangles(mesh)
    vertex = np.dtype([("p", "<f4", 3), ("n", "<f4", 3), ("c", "u1", 4)])
    face = np.dtype([("k", "u1"), ("v", "<i4", 3)])
    assert len(body) == n_vertices * vertex.itemsize + n_faces * face.itemsize
    faces = np.frombuffer(body, face, offset=n_vertices * vertex.itemsize)
    assert (faces["k"] == 3).all() and faces["v"].min() == 0 and faces["v"].max() == n_vertices - 1
    colours = {tuple(c) for c in np.frombuffer(body, vertex, count=n_vertices)["c"].tolist()}
    assert {tuple(round(v * 255) for v in (*BARK, 1.0)), tuple(round(v * 255) for v in (*LEAF, 1.0))} <= colours
    back = pv.read(path)  # VTK's reader agrees
    assert back.n_cells == n_faces and back.is_all_triangles and "RGBA" in back.point_data
