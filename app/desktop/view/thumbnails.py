"""Small pictures of plants drawn with QPainter on a QImage (safe in worker threads).

Thumbnails (the variant gallery, the qualifier preview, the study's 27
images when an exploration has none) draw the skeleton as lines seen from
the front (x right, z up), line width from the segment radius, organs as
dots, polygons (``{ . }`` leaves and petals) filled in the leaf colour (at
most :data:`MAX_POLYGONS`, evenly picked, so a huge plant stays quick).
No OpenGL is involved, so many can be drawn in a worker while the 3D view
keeps the GL context.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from PySide6.QtCore import QLineF, QPointF, QRectF, Qt
from PySide6.QtGui import QColor, QImage, QPainter, QPen, QPolygonF

from ramure.app.render import BARK, FRUIT, LEAF

if TYPE_CHECKING:
    from ramure.lsys.interpretation.turtle import Skeleton


#: The most polygons a thumbnail fills (beyond, every k-th one).
MAX_POLYGONS = 20_000


def _qcolor(rgb):
    return QColor.fromRgbF(*rgb)


#: The colour of a variant's segments that are the plant's own (:func:`same_segments`).
SAME_RGB = (0.78, 0.76, 0.74)


def same_segments(skeleton: Skeleton, base: Skeleton, decimals: int = 5) -> np.ndarray:
    """Bool per segment of ``skeleton``: True where ``base`` has a segment at the same place (the
    same start and end to ``decimals`` places), so a variant's thumbnail can grey out what it
    shares with the plant and show the part that differs."""

    def rows(sk):
        ends = np.round(np.c_[np.asarray(sk.start), np.asarray(sk.end)].astype(np.float64), decimals) + 0.0  # no -0.0
        return np.ascontiguousarray(ends).view(np.dtype((np.void, ends.dtype.itemsize * 6))).ravel()

    return np.isin(rows(skeleton), rows(base))


def skeleton_image(
    skeleton: Skeleton, size: int = 160, label: str | None = None, background: str = "white", same: np.ndarray | None = None
) -> QImage:
    """A ``size`` x ``size`` QImage of a skeleton, front view, with an optional corner label.
    ``same``: bool per segment, drawn pale (the plant's own), so the part that differs stands out."""
    image = QImage(size, size, QImage.Format.Format_RGB32)
    image.fill(QColor(background))
    painter = QPainter(image)
    painter.setRenderHint(QPainter.RenderHint.Antialiasing)
    start, end = np.asarray(skeleton.start), np.asarray(skeleton.end)
    organs = skeleton.organs
    pts = [start[:, [0, 2]], end[:, [0, 2]]]
    if len(organs):
        pts.append(np.asarray(organs.position)[:, [0, 2]])
    polygons = getattr(skeleton, "polygons", None)
    if polygons is not None and len(polygons):
        pts.append(np.asarray(polygons.points)[:, [0, 2]])
    allpts = np.concatenate(pts) if any(len(p) for p in pts) else np.zeros((1, 2))
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    span = float(max(hi[0] - lo[0], hi[1] - lo[1], 1e-9))
    margin = 0.06 * size
    scale = (size - 2 * margin) / span
    cx = (lo[0] + hi[0]) / 2

    def to_px(xz):
        return np.c_[size / 2 + (xz[:, 0] - cx) * scale, size - margin - (xz[:, 1] - lo[1]) * scale]

    a, b = to_px(start[:, [0, 2]]), to_px(end[:, [0, 2]])
    widths = np.clip(2 * np.asarray(skeleton.base_radius) * scale, 0.6, size / 12)
    pen = QPen(_qcolor(BARK))
    pen.setCapStyle(Qt.PenCapStyle.RoundCap)
    pale = np.zeros(len(widths), bool) if same is None else np.asarray(same, bool)
    order = np.lexsort((-widths, ~pale))  # the shared part first, then the differing part; thick first
    bark, shared = _qcolor(BARK), _qcolor(SAME_RGB)
    for i in order.tolist():
        pen.setWidthF(float(widths[i]))
        pen.setColor(shared if pale[i] else bark)
        painter.setPen(pen)
        painter.drawLine(QLineF(a[i, 0], a[i, 1], b[i, 0], b[i, 1]))
    if polygons is not None and len(polygons):
        _fill_polygons(painter, polygons, to_px)
    if len(organs):
        p = to_px(np.asarray(organs.position)[:, [0, 2]])
        radius = np.clip(np.asarray(organs.size) * scale / 2, 1.0, size / 15)
        painter.setPen(Qt.PenStyle.NoPen)
        for (x, y), r, kind in zip(p.tolist(), radius.tolist(), list(organs.kind)):
            painter.setBrush(_qcolor(FRUIT if kind == "Fruit" else LEAF))
            painter.drawEllipse(QPointF(x, y), r, r)
    if label:
        painter.setPen(QColor("black"))
        font = painter.font()
        font.setPixelSize(max(9, size // 10))
        painter.setFont(font)
        painter.drawText(QRectF(3, 2, size - 6, size // 6), Qt.AlignmentFlag.AlignLeft, str(label))
    painter.end()
    return image


def _fill_polygons(painter, polygons, to_px):
    """Each polygon (seen from the front) filled in the leaf colour."""
    px = to_px(np.asarray(polygons.points)[:, [0, 2]]).tolist()
    offsets = np.asarray(polygons.offsets).tolist()
    painter.setPen(Qt.PenStyle.NoPen)
    painter.setBrush(_qcolor(LEAF))
    for k in range(0, len(polygons), max(1, -(-len(polygons) // MAX_POLYGONS))):
        painter.drawPolygon(QPolygonF([QPointF(x, y) for x, y in px[offsets[k] : offsets[k + 1]]]))


def placeholder_image(size: int = 160, label: str = "", note: str = "no image") -> QImage:
    """A grey tile with a label, for a pick whose plant cannot be drawn."""
    image = QImage(size, size, QImage.Format.Format_RGB32)
    image.fill(QColor("#eeeeee"))
    painter = QPainter(image)
    painter.setPen(QColor("#555555"))
    font = painter.font()
    font.setPixelSize(max(10, size // 6))
    painter.setFont(font)
    painter.drawText(QRectF(0, 0, size, size * 0.7), Qt.AlignmentFlag.AlignCenter, str(label))
    font.setPixelSize(max(8, size // 12))
    painter.setFont(font)
    painter.drawText(QRectF(0, size * 0.6, size, size * 0.3), Qt.AlignmentFlag.AlignCenter, note)
    painter.end()
    return image


def image_is_blank(image: QImage, threshold: float = 1.0) -> bool:
    """True when a QImage has (almost) no pixel variance: the test of "something was drawn"."""
    return pixel_variance(image) <= threshold


def pixel_variance(image: QImage) -> float:
    """The variance of the grey levels of a QImage."""
    img = image.convertToFormat(QImage.Format.Format_Grayscale8)
    width, height, stride = img.width(), img.height(), img.bytesPerLine()
    data = np.frombuffer(img.constBits(), np.uint8, count=stride * height).reshape(height, stride)[:, :width]
    return float(data.astype(float).var())
