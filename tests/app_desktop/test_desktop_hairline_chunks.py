"""The hairlines drawn in chunks, each after the last was drawn (issue 14: the desktop's memory):
every line once, in order, the same pixels as one draw, one wait per chunk after the first."""

from __future__ import annotations

import numpy as np
import pytest

from ramure.app.desktop.view import plant_actors, scene
from desktop_helpers import settle
from test_desktop_draft_frame import image_array, lines_drawn


@pytest.fixture
def waits(monkeypatch):
    """The waits for completion the chunk actors ask for (counted, then done)."""
    calls = []
    real = scene.LineChunks._wait

    def wait(self, *args):
        calls.append(self)
        real(self, *args)

    monkeypatch.setattr(scene.LineChunks, "_wait", wait)
    return calls


def test_small_chunks_draw_every_line_once_in_order_and_wait_before_each(make_window, qtbot, waits, monkeypatch):
    monkeypatch.setattr(scene, "CHUNK_LINES", 100)
    w = make_window(n=10)  # 1,023 segments: 11 chunks
    view = w.view
    shown = view.hairlines.shown
    drawn, conn = lines_drawn(view)
    assert len(drawn) == len(view.hairlines.actors) == 11
    assert all(d.GetNumberOfCells() <= 100 for d in drawn)
    np.testing.assert_array_equal(conn, shown.conn)  # every line, once, in the line set's order
    assert all(d.GetPoints() is shown.lines.GetPoints() for d in drawn)  # one upload of the points
    del waits[:]
    view.redraw(now=True)
    assert len(waits) == 10  # before every chunk but the first
    # a regrow: the new version's chunks, the old ones kept hidden for the undo
    old = list(view.hairlines.actors)
    snap = w.controller.snapshot
    w.controller.select([int(v) for v in snap.segment_leaf[::97][:5]])
    settle(qtbot, w)
    w.controller.regrow(seed=2)
    settle(qtbot, w)
    np.testing.assert_array_equal(lines_drawn(view)[1], view.hairlines.shown.conn)
    assert not any(a.GetVisibility() for a in old) and all(a.GetVisibility() for a in view.hairlines.actors)
    w.controller.undo()
    settle(qtbot, w)
    assert view.hairlines.actors == old and all(a.GetVisibility() for a in old)


def test_chunks_draw_the_pixels_of_one_draw(make_window, qtbot, monkeypatch):
    pictures = []
    for chunk in (10**9, 150):
        monkeypatch.setattr(scene, "CHUNK_LINES", chunk)
        w = make_window(n=11)
        assert len(w.view.hairlines.actors) == (1 if chunk > 10**6 else 14)
        for draft in (False, True):
            w.view.draft() if draft else w.view.polish()
            w.view.redraw(now=True)
            pictures.append(image_array(w.view.frame_image()))
        w.dirty = False
        w.close()
    polished, draft, chunked_polished, chunked_draft = pictures
    assert len(np.unique(polished.reshape(-1, 3), axis=0)) > 20  # a plant, not a blank view
    np.testing.assert_array_equal(chunked_polished, polished)
    np.testing.assert_array_equal(chunked_draft, draft)


def test_a_draft_takes_the_first_chunks_it_needs_of_the_same_actors(make_window, qtbot, waits, monkeypatch):
    monkeypatch.setattr(scene, "CHUNK_LINES", 200)
    monkeypatch.setattr(scene, "DRAFT_MIN_LEFT_OUT", 0.0)
    monkeypatch.setattr(plant_actors, "LOD_SEGMENTS", 500)  # drawn as a large plant: drafts
    w = make_window(n=10)
    view = w.view
    actors = list(view.hairlines.actors)
    view.plotter.camera.Zoom(0.3)  # far: many lines shorter than the draft's threshold
    view.draft()
    view.redraw(now=True)
    drawn, conn = lines_drawn(view)
    assert view.hairlines.actors == actors and len(drawn) == len(actors) == 6  # 1,023 lines
    assert 200 < len(conn) < 800  # the lines long enough on screen: 2 to 4 chunks
    assert (np.diff(conn[:, 0]) > 0).all()  # ascending: the order of the one draw
    used = -(-len(conn) // 200)
    sizes = [d.GetNumberOfCells() for d in drawn]
    assert all(0 < k <= 200 for k in sizes[:used]) and not any(sizes[used:])
    del waits[:]
    view.redraw(now=True)
    assert len(waits) == used - 1  # the empty chunks draw nothing and wait for nothing


def test_new_colours_show_in_the_next_frame_in_every_chunk(qtbot, monkeypatch):
    """Colours written in place are uploaded again (VTK draws four-byte colours as they are, from
    one buffer per array): a recolour, and the recolour of a version an undo shows again."""
    import pyvista as pv

    from ramure.app.desktop.view import plant_actors
    from ramure.app.model import Explorer
    from desktop_helpers import HONDA

    monkeypatch.setattr(scene, "CHUNK_LINES", 100)
    plotter = pv.Plotter(off_screen=True, window_size=(400, 400))
    lines = scene.Hairlines(plotter)
    ex = Explorer(str(HONDA), n=9)

    def paint(rgb):
        return np.tile(np.array([rgb], np.uint8), (ex.mesh.n_cells, 1))

    def shown_in(picture, channel):  # pixels of a saturated red (0) or blue (2)
        other = 2 - channel
        return int(((picture[..., channel] > 150) & (picture[..., other] < 80)).sum())

    def frame():
        plotter.render()
        return plotter.screenshot(return_img=True).astype(int)

    first, skeleton = ex.mesh, ex.skeleton
    sides = plant_actors.tube_layout(first, len(skeleton))
    lines.show(skeleton, first, paint((200, 0, 0)), key=first, sides=sides)
    assert len(lines.actors) == 6  # 511 lines
    plotter.reset_camera()
    red = shown_in(frame(), 0)
    assert red > 500
    lines.set_colors(first, paint((0, 0, 200)))
    picture = frame()
    assert shown_in(picture, 2) == red and shown_in(picture, 0) == 0
    # another version, then back to the first (an undo) in new colours
    ex.select(ex.skeleton.leaf_id[::50].tolist())
    ex.regrow(seed=1)
    lines.show(ex.skeleton, ex.mesh, paint((0, 0, 200)), key=ex.mesh, sides=plant_actors.tube_layout(ex.mesh, len(ex.skeleton)))
    frame()
    lines.show(skeleton, first, paint((200, 0, 0)), key=first, sides=sides)  # the kept version again
    assert lines.shown is not None and lines.shown.key is first
    picture = frame()
    assert shown_in(picture, 0) == red and shown_in(picture, 2) == 0
    plotter.close()
