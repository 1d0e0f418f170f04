"""Render the G-map guide's pictures (``docs/gmap.md``) from real :class:`~ramure.gmap.GMap3` maps.

Run from the repository root (``.venv/bin/python docs/images/make_gmap_pictures.py``); it
rewrites ``docs/images/gmap_*.png`` with matplotlib, off-screen.  Each dart is drawn the way
CGAL's manual and Lienhardt draw them: a short arrow from near its vertex towards the middle
of its edge, pulled into its face and its volume, so the darts of one edge, one face and one
volume stand apart; the involutions are the thin links between them.
"""

from __future__ import annotations

import io
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the off-screen backend)
import numpy as np  # noqa: E402

import ramure.io  # noqa: E402
from ramure.gmap import GMap3  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
#: one colour per involution, the same in every picture
COLOURS = {0: "#d62728", 1: "#1f77b4", 2: "#2ca02c", 3: "#9467bd"}


def centres(gm: GMap3, cells: str) -> np.ndarray:
    """(n, 3) the centre of each dart's orbit under ``cells`` (its face "01", its volume "012")."""
    pts = np.asarray(gm.points, float)
    ids, count = gm.orbit_ids(cells)
    sums = np.stack([np.bincount(ids, pts[:, j], minlength=count) for j in range(3)], axis=1)
    return (sums / np.bincount(ids, minlength=count)[:, None])[ids]


def dart_segments(gm: GMap3, explode: float = 0.14, shrink: float = 0.12) -> np.ndarray:
    """(n, 2, 3) start and end of each dart's arrow: from near its vertex to near its edge's
    middle, pulled by ``shrink`` towards its face centre and by ``explode`` towards its volume's."""
    pts = np.asarray(gm.points, float)
    mid = (pts + pts[gm.alpha[0]]) / 2
    start, end = pts + 0.42 * (mid - pts), pts + 0.9 * (mid - pts)
    pull = shrink * (centres(gm, "01") - mid) + explode * (centres(gm, "012") - mid)  # across the edge only
    return np.stack([start + pull, end + pull], axis=1)


def links(gm: GMap3, i: int, darts: np.ndarray) -> np.ndarray:
    """Pairs ``(d, alpha_i d)`` with ``d < alpha_i d`` among ``darts`` (each link once, free darts left out)."""
    partner = gm.alpha[i][darts]
    keep = (darts < partner) & np.isin(partner, darts)
    return np.stack([darts[keep], partner[keep]], axis=1)


#: where on its dart (0 tail, 1 head) a link of each involution starts: alpha0 joins the heads
#: (the middle of the edge), alpha1 the tails (the corner), alpha2 and alpha3 the middles
LINK_AT = {0: 0.95, 1: 0.05, 2: 0.5, 3: 0.5}


def link_curve(a: np.ndarray, b: np.ndarray, towards: np.ndarray, bulge: float = 0.35) -> np.ndarray:
    """(12, k) points of a small arc from ``a`` to ``b`` bent towards ``towards``."""
    control = (a + b) / 2 + bulge * (towards - (a + b) / 2) * np.linalg.norm(b - a)
    t = np.linspace(0, 1, 12)[:, None]
    return (1 - t) ** 2 * a + 2 * t * (1 - t) * control + t**2 * b


def draw(ax, gm: GMap3, darts: np.ndarray, involutions: tuple[int, ...], labels: bool = False, plane=None) -> None:
    """Draw ``darts`` and their links by ``involutions`` on ``ax`` (3D, or 2D through ``plane`` (3, 2))."""
    seg = dart_segments(gm)
    face = centres(gm, "01") * 0.5 + centres(gm, "012") * 0.5

    def project(p):
        return p if plane is None else p @ plane

    for i in involutions:
        for a, b in links(gm, i, darts):
            pa, pb = (seg[d, 0] + LINK_AT[i] * (seg[d, 1] - seg[d, 0]) for d in (a, b))
            bend = 0.0 if i >= 2 else 0.35
            ax.plot(*project(link_curve(pa, pb, face[a], bend)).T, color=COLOURS[i], lw=2.0)
    for d in darts:
        a, b = project(seg[d])
        if plane is None:
            ax.plot(*np.stack([a, b]).T, color="black", lw=1.3)
            ax.scatter(*b, color="black", s=5)
        else:
            ax.annotate("", xy=b, xytext=a, arrowprops={"arrowstyle": "-|>", "lw": 1.4, "color": "black"})
            if labels:
                inside = project(face[d]) - (a + b) / 2
                ax.text(*((a + b) / 2 + 0.09 * inside / np.linalg.norm(inside)), str(d), fontsize=10, ha="center", va="center")


def legend(fig, involutions: tuple[int, ...]) -> None:
    handles = [plt.Line2D([], [], color=COLOURS[i], lw=2, label=f"alpha{i}") for i in involutions]
    handles.insert(0, plt.Line2D([], [], color="black", lw=1.4, label="dart"))
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), frameon=False)


def face_picture() -> plt.Figure:
    """The O face of a cube: 8 darts, alpha0 pairs them along an edge, alpha1 at a corner."""
    gm = GMap3()
    gm.add_prisms(4)
    fig, ax = plt.subplots(figsize=(4.8, 5.0))
    plane = np.array([[0, 0], [1, 0], [0, 1]], float)  # the O face lies in x = 0: (y, z)
    draw(ax, gm, gm.orbit(0, "01"), (0, 1), labels=True, plane=plane)
    ax.set_aspect("equal")
    ax.axis("off")
    legend(fig, (0, 1))
    return fig


def cube_picture() -> plt.Figure:
    """A cube's 48 darts: six faces of 8, alpha2 joins the faces along each edge."""
    gm = GMap3()
    gm.add_prisms(4)
    fig = plt.figure(figsize=(4.6, 4.6))
    ax = fig.add_subplot(projection="3d")
    draw(ax, gm, np.arange(gm.n_darts), (0, 1, 2))
    _frame(ax)
    legend(fig, (0, 1, 2))
    return fig


def sew_picture() -> plt.Figure:
    """Two cubes 3-sewn along a face: alpha3 links the 8 darts of one face to the other's."""
    gm = GMap3()
    first = gm.add_prisms(4, count=2, origins=[[0, 0, 0], [1, 0, 0]])
    gm.sew(3, gm.prism_face(first[0], 4, "E"), gm.prism_face(first[1], 4, "O"))
    fig = plt.figure(figsize=(7.5, 4.6))
    ax = fig.add_subplot(projection="3d")
    draw(ax, gm, np.arange(gm.n_darts), (3,))
    _frame(ax, box=(2, 1, 1), azim=-75)
    legend(fig, (3,))
    return fig


def _frame(ax, box=(1, 1, 1), azim: float = -58) -> None:
    ax.set_box_aspect(box)
    ax.view_init(elev=22, azim=azim)
    ax.set_axis_off()


PICTURES = {"gmap_face.png": face_picture, "gmap_cube.png": cube_picture, "gmap_sew.png": sew_picture}


def main() -> None:
    for name, make in PICTURES.items():
        fig = make()
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", dpi=90, bbox_inches="tight")
        plt.close(fig)
        ramure.io.write_bytes(HERE / name, buffer.getvalue())
        print(f"wrote {HERE / name}")


if __name__ == "__main__":
    main()
