"""Ramure's small PlantGL: the objects L-Py models use most, for :mod:`ramure.lsys.readers.lpy`.

``Vector2``/``Vector3`` (arithmetic, ``norm``, ``normalize``, ``^`` the cross product, ``*`` between
two vectors the dot product), ``Color3``/``Color4``, ``Material`` (its colour is ``ambient`` times
``diffuse``, as PlantGL draws it), the curves ``Polyline2D``, ``BezierCurve2D`` and ``NurbsCurve2D``
(evaluated with ``getPointAt(u)`` for ``u`` from ``firstKnot`` to ``lastKnot``) and
``QuantisedFunction`` (a curve sampled as a function ``y(x)``).  Nothing else of PlantGL is
here: a model asking for another name is refused, naming it.

>>> c = NurbsCurve2D(Point3Array([(0, 0, 1), (0.5, 1, 1), (1, 0, 1)]), degree=2)
>>> tuple(round(v, 3) for v in c.getPointAt(0.5))
(0.5, 0.5)
>>> QuantisedFunction(Polyline2D([(0, 0), (1, 2)]))(0.25)
0.5
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np


class Vector3:
    """A 3D vector (PlantGL's ``Vector3``)."""

    size = 3

    def __init__(self, *values: Any) -> None:
        if len(values) == 1 and isinstance(values[0], Iterable):
            values = tuple(values[0])
        data = np.zeros(self.size)
        data[: len(values)] = [float(v) for v in values]
        self.data = data

    @classmethod
    def _of(cls, data: np.ndarray) -> Any:
        out = cls.__new__(cls)
        out.data = np.asarray(data, float)
        return out

    x = property(lambda self: float(self.data[0]), lambda self, v: self.data.__setitem__(0, v))
    y = property(lambda self: float(self.data[1]), lambda self, v: self.data.__setitem__(1, v))
    z = property(lambda self: float(self.data[2]), lambda self, v: self.data.__setitem__(2, v))

    def __iter__(self):
        return iter(self.data.tolist())

    def __len__(self) -> int:
        return self.size

    def __getitem__(self, i: int) -> float:
        return float(self.data[i])

    def __setitem__(self, i: int, v: float) -> None:
        self.data[i] = v

    def __add__(self, other: Any) -> Any:
        return self._of(self.data + _data(other))

    __radd__ = __add__

    def __sub__(self, other: Any) -> Any:
        return self._of(self.data - _data(other))

    def __rsub__(self, other: Any) -> Any:
        return self._of(_data(other) - self.data)

    def __mul__(self, other: Any) -> Any:
        if isinstance(other, Vector3):
            return float(self.data @ other.data)
        return self._of(self.data * float(other))

    __rmul__ = __mul__

    def __truediv__(self, other: float) -> Any:
        return self._of(self.data / float(other))

    def __neg__(self) -> Any:
        return self._of(-self.data)

    def __xor__(self, other: Any) -> Any:
        return self._of(np.cross(self.data, _data(other)))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Vector3) and bool(np.array_equal(self.data, other.data))

    __hash__ = None  # type: ignore[assignment]  # mutable, as in PlantGL

    def __repr__(self) -> str:
        return f"{type(self).__name__}({', '.join(repr(v) for v in self)})"

    def __norm__(self) -> float:
        return float(np.linalg.norm(self.data))

    def normalize(self) -> float:
        """Make the vector unit length in place; returns its former length."""
        n = self.__norm__()
        if n > 0:
            self.data = self.data / n
        return n

    def normed(self) -> Any:
        n = self.__norm__()
        return self._of(self.data / n if n > 0 else self.data)


Vector3.OX, Vector3.OY, Vector3.OZ = (Vector3(*row) for row in np.eye(3))  # type: ignore[attr-defined]  # PlantGL's axes


class Vector2(Vector3):
    """A 2D vector (PlantGL's ``Vector2``)."""

    size = 2
    z = property(lambda self: 0.0)  # a 2D vector has no z


Vector2.OX, Vector2.OY = Vector2(1, 0), Vector2(0, 1)  # type: ignore[attr-defined]  # PlantGL's axes


class Vector4(Vector3):
    """A 4D vector (PlantGL's ``Vector4``), e.g. a weighted control point."""

    size = 4
    w = property(lambda self: float(self.data[3]))


def _data(v: Any) -> np.ndarray:
    return v.data if isinstance(v, Vector3) else np.asarray(v, float)


def norm(v: Any) -> float:
    """The Euclidean length of ``v``."""
    return float(np.linalg.norm(_data(v)))


def cross(a: Any, b: Any) -> Any:
    """The cross product ``a x b`` (of two 2D vectors: the number ``ax*by - ay*bx``)."""
    u, v = _data(a), _data(b)
    if len(u) == 2 and len(v) == 2:
        return float(u[0] * v[1] - u[1] * v[0])
    return Vector3(np.cross(u, v))


def angle(a: Any, b: Any, axis: Any = None) -> float:
    """The angle from ``a`` to ``b`` in radians: signed for 2D vectors, in [0, pi] for 3D ones, and
    signed about ``axis`` when one is given (positive when ``a x b`` points along it)."""
    u, v = _data(a), _data(b)
    if len(u) == 2 and len(v) == 2:
        return math.atan2(cross(u, v), float(u @ v))
    turn = np.cross(u, v)
    unsigned = math.atan2(float(np.linalg.norm(turn)), float(u @ v))
    return -unsigned if axis is not None and float(turn @ _data(axis)) < 0 else unsigned


def dot(a: Any, b: Any) -> float:
    """The dot product of ``a`` and ``b``."""
    return float(_data(a) @ _data(b))


class Matrix3:
    """A 3x3 matrix (PlantGL's ``Matrix3``): ``m * v`` turns a vector, ``m * n`` composes."""

    def __init__(self, *rows: Any) -> None:
        self.data = np.array(rows, float).reshape(3, 3) if rows else np.eye(3)

    @staticmethod
    def axisRotation(axis: Any, angle: float) -> Matrix3:
        """The rotation by ``angle`` radians about ``axis`` (right hand), Rodrigues' formula."""
        k = _data(axis) / np.linalg.norm(_data(axis))
        cross_k = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        out = Matrix3()
        out.data = np.eye(3) + math.sin(angle) * cross_k + (1 - math.cos(angle)) * cross_k @ cross_k
        return out

    def __mul__(self, other: Any) -> Any:
        if isinstance(other, Matrix3):
            out = Matrix3()
            out.data = self.data @ other.data
            return out
        return Vector3(self.data @ _data(other))


class Color3:
    """An RGB colour, components 0..255 (PlantGL's ``Color3``)."""

    def __init__(self, red: int = 0, green: int = 0, blue: int = 0) -> None:
        if isinstance(red, Iterable):
            red, green, blue = list(red)[:3]
        self.red, self.green, self.blue = int(red), int(green), int(blue)

    def __iter__(self):
        return iter((self.red, self.green, self.blue))

    def __repr__(self) -> str:
        return f"Color3({self.red},{self.green},{self.blue})"

    def rgb01(self) -> tuple[float, float, float]:
        """The colour with components 0..1."""
        return (self.red / 255, self.green / 255, self.blue / 255)


class Color4(Color3):
    """An RGBA colour (PlantGL's ``Color4``)."""

    def __init__(self, red: int = 0, green: int = 0, blue: int = 0, alpha: int = 0) -> None:
        super().__init__(red, green, blue)
        self.alpha = int(alpha)


class Material:
    """A material: its drawn colour is ``ambient * diffuse`` (0..255), with ``transparency``."""

    def __init__(
        self,
        name: Any = "",
        ambient: Any = (80, 80, 80),
        diffuse: float = 2.0,
        specular: Any = None,
        emission: Any = None,
        shininess: float = 0.2,
        transparency: float = 0.0,
        **other: Any,
    ) -> None:
        if not isinstance(name, str):  # Material(ambient, diffuse, specular, emission, shininess, transparency)
            name, ambient, diffuse, specular, emission, shininess, transparency = (
                "", name, ambient, diffuse, specular, emission, shininess
            )  # fmt: skip
            diffuse = 2.0 if isinstance(diffuse, tuple) else diffuse
        self.name = name
        self.specular, self.emission, self.shininess = specular, emission, shininess
        self.ambient = Color3(*ambient) if not isinstance(ambient, Color3) else ambient
        self.diffuse = float(diffuse)
        self.transparency = float(transparency)
        self.other = other

    def rgba(self) -> tuple[float, float, float, float]:
        """The drawn colour, components 0..1."""
        r, g, b = (min(1.0, c * self.diffuse / 255) for c in self.ambient)
        return (r, g, b, 1.0 - self.transparency)


def Point2Array(points: Iterable[Any] = ()) -> list[Vector2]:
    """A list of 2D points."""
    return [Vector2(p) for p in points]


def Point3Array(points: Iterable[Any] = ()) -> list[Vector3]:
    """A list of 3D points (for curves: x, y and a weight)."""
    return [Vector3(p) for p in points]


def Point4Array(points: Iterable[Any] = ()) -> list[Vector4]:
    """A list of 4D points."""
    return [Vector4(p) for p in points]


class Curve2D:
    """A planar curve: ``getPointAt(u)`` for ``u`` in ``[firstKnot, lastKnot]``."""

    firstKnot = 0.0
    lastKnot = 1.0

    def __init__(self, ctrlPointList: Sequence[Any] = (), **options: Any) -> None:
        self.ctrlPointList = [p for p in ctrlPointList]
        self.options = options
        self.name = ""

    #: coordinates of a point (2 for the 2D curves, 3 for the 3D ones); a control point may
    #: carry one more value, its weight
    dim = 2

    def _points(self, homogeneous: bool) -> np.ndarray:
        pts = np.array([list(p)[: self.dim + 1] for p in self.ctrlPointList], float)
        if pts.shape[1] == self.dim:
            pts = np.c_[pts, np.ones(len(pts))]
        if homogeneous:
            pts[:, : self.dim] *= pts[:, self.dim : self.dim + 1]
        return pts

    def _point(self, values: np.ndarray) -> Vector3:
        return Vector2(values) if self.dim == 2 else Vector3(values)

    def getPointAt(self, u: float) -> Vector3:
        raise NotImplementedError

    def getTangentAt(self, u: float) -> Vector2:
        """The derivative at ``u`` (central differences)."""
        h = (self.lastKnot - self.firstKnot) * 1e-4
        a = self.getPointAt(max(self.firstKnot, u - h))
        b = self.getPointAt(min(self.lastKnot, u + h))
        return (b - a) / (min(self.lastKnot, u + h) - max(self.firstKnot, u - h))

    def getLength(self, begin: float | None = None, end: float | None = None) -> float:
        """The arc length from ``begin`` to ``end`` (the whole curve by default), over 200 chords."""
        us = np.linspace(self.firstKnot if begin is None else begin, self.lastKnot if end is None else end, 201)
        pts = np.array([list(self.getPointAt(float(u))) for u in us])
        return float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())

    def getArcLengthToUMapping(self) -> QuantisedFunction:
        """The parameter ``u`` at each fraction (0..1) of the curve's arc length."""
        us = np.linspace(self.firstKnot, self.lastKnot, 201)
        pts = np.array([list(self.getPointAt(float(u))) for u in us])
        s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))]
        return QuantisedFunction(Polyline2D(np.c_[s / s[-1] if s[-1] > 0 else s, us]), sampling=201)

    def deepcopy(self) -> Any:
        import copy

        return copy.deepcopy(self)

    def points(self, count: int) -> np.ndarray:
        """``count`` points evenly spaced in the parameter, as an array (count, 2)."""
        us = np.linspace(self.firstKnot, self.lastKnot, count)
        return np.array([list(self.getPointAt(float(u))) for u in us])


class Polyline2D(Curve2D):
    """A polyline, parameter from 0 to the number of segments (as PlantGL)."""

    def __init__(self, pointList: Sequence[Any] = (), **options: Any) -> None:
        super().__init__(pointList, **options)
        self.lastKnot = float(max(len(self.ctrlPointList) - 1, 0))

    def getPointAt(self, u: float) -> Vector3:
        pts = self._points(False)[:, : self.dim]
        u = min(max(float(u), 0.0), self.lastKnot)
        i = min(int(math.floor(u)), len(pts) - 2)
        if i < 0:
            return self._point(pts[0])
        t = u - i
        return self._point(pts[i] * (1 - t) + pts[i + 1] * t)


class BezierCurve2D(Curve2D):
    """A rational Bezier curve (control points x, y, weight), de Casteljau's evaluation."""

    def getPointAt(self, u: float) -> Vector3:
        pts = self._points(True)
        t = min(max(float(u), 0.0), 1.0)
        while len(pts) > 1:
            pts = pts[:-1] * (1 - t) + pts[1:] * t
        return self._point(pts[0, : self.dim] / pts[0, self.dim])


class NurbsCurve2D(Curve2D):
    """A rational B-spline (PlantGL's ``NurbsCurve2D``): a clamped uniform knot vector unless
    ``knotList`` is given, degree 3 unless ``degree`` is (at most the number of points - 1)."""

    def __init__(self, ctrlPointList: Sequence[Any] = (), knotList: Any = None, degree: int = 3, **options: Any) -> None:
        super().__init__(ctrlPointList, **options)
        n = len(self.ctrlPointList)
        self.degree = max(1, min(int(degree), n - 1))
        if knotList is None:
            inner = np.linspace(0, 1, n - self.degree + 1)
            knotList = np.r_[np.zeros(self.degree), inner, np.ones(self.degree)]
        self.knotList = np.asarray(list(knotList), float)
        self.firstKnot, self.lastKnot = float(self.knotList[self.degree]), float(self.knotList[n])

    def getPointAt(self, u: float) -> Vector3:
        pts, knots, p = self._points(True), self.knotList, self.degree
        u = min(max(float(u), self.firstKnot), self.lastKnot)
        k = int(np.searchsorted(knots, u, side="right")) - 1
        k = min(max(k, p), len(pts) - 1)
        d = pts[k - p : k + 1].copy()
        for r in range(1, p + 1):  # de Boor
            for j in range(p, r - 1, -1):
                i = j + k - p
                span = knots[i + p - r + 1] - knots[i]
                a = 0.0 if span == 0 else (u - knots[i]) / span
                d[j] = (1 - a) * d[j - 1] + a * d[j]
        return self._point(d[p, : self.dim] / d[p, self.dim])


class Polyline(Polyline2D):
    """A 3D polyline (PlantGL's ``Polyline``)."""

    dim = 3


class BezierCurve(BezierCurve2D):
    """A 3D rational Bezier curve, control points x, y, z and a weight (PlantGL's ``BezierCurve``)."""

    dim = 3


class NurbsCurve(NurbsCurve2D):
    """A 3D rational B-spline, control points x, y, z and a weight (PlantGL's ``NurbsCurve``)."""

    dim = 3


class QuantisedFunction:
    """A curve read as a function ``y(x)``, sampled ``sampling`` times and interpolated."""

    def __init__(self, curve: Any, sampling: int = 100, clamped: bool = True) -> None:
        if not isinstance(curve, Curve2D):  # a list of (x, y) points
            curve = Polyline2D(curve)
            sampling = max(int(sampling), 10 * len(curve.ctrlPointList))
        pts = curve.points(max(int(sampling), 2))
        order = np.argsort(pts[:, 0], kind="stable")
        self.x, self.y = pts[order, 0], pts[order, 1]
        self.clamped = clamped

    def __call__(self, x: float) -> float:
        return float(np.interp(float(x), self.x, self.y))

    def getValue(self, x: float) -> float:
        return self(x)


class ParameterSet:
    """L-Py's ``ParameterSet`` (from ``openalea.lpy``): named values read and set as attributes,
    the parameter bag of a module (``I(ParameterSet(diameter=0.1))``, then ``p.diameter``).

    >>> p = ParameterSet(age=0); q = p.copy(); q.age += 1
    >>> p.age, q.age, q.hasattr("age"), p.parameter_names()
    (0, 1, True, ['age'])
    """

    def __init__(self, **values: Any) -> None:
        self.__dict__.update(values)

    def copy(self) -> ParameterSet:
        """A new set with the same values (a shallow copy, as L-Py's)."""
        return ParameterSet(**self.__dict__)

    def set(self, **values: Any) -> None:
        """Set several values at once."""
        self.__dict__.update(values)

    def setdefault(self, **values: Any) -> None:
        """Set the values not set yet."""
        for name, value in values.items():
            self.__dict__.setdefault(name, value)

    def hasattr(self, name: str) -> bool:
        """Whether the set has a value of that name."""
        return name in self.__dict__

    def parameter_names(self) -> list[str]:
        """The names set, in the order they were set."""
        return list(self.__dict__)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ParameterSet) and self.__dict__ == other.__dict__

    def __repr__(self) -> str:
        return f"ParameterSet({', '.join(f'{k}={v!r}' for k, v in self.__dict__.items())})"


def names() -> dict[str, Any]:
    """Every name of this small PlantGL (what ``from openalea.plantgl.all import *`` gives)."""
    shown = (
        Vector2, Vector3, Vector4, Color3, Color4, Material, Polyline2D, BezierCurve2D, NurbsCurve2D,
        Polyline, BezierCurve, NurbsCurve, QuantisedFunction, Point2Array, Point3Array, Point4Array, norm, cross,
        dot, angle, Matrix3,
    )  # fmt: skip
    return {f.__name__: f for f in shown}
