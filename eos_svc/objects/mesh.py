"""The mesh: a triangle mesh read from a file or given inline, scaled and placed.

JSON form (either a file or the mesh itself; ``scale`` multiplies the coordinates, default 1)::

    {"shape": "mesh", "file": "mug.obj", "scale": 0.001, "position": [...], "rpy": [...]}
    {"shape": "mesh", "vertices": [[x, y, z], ...], "faces": [[i, j, k], ...], "scale": 1.0, ...}

trimesh (https://trimesh.org) reads OBJ, STL and PLY. The object frame is the mesh's own axes
moved to its **centre of mass** (the solid's, when the mesh is closed; else its convex hull's):
``position`` places the centre of mass, as it places a primitive's centre.

- signed distance: the distance to the nearest triangle (coal, ``BVHModelOBBRSS``), negative
  inside, inside meaning a generalised winding number above ½ (Jacobson, Kavan, Sorkine-Hornung,
  SIGGRAPH 2013: exact for closed meshes, robust for open ones; for a convex one, inside every
  face's plane); its gradient points from the
  nearest surface point to the point (the nearest triangle's normal on the surface);
- curvature: zero on every face (a polygon mesh is flat between its edges);
- coal shape: the mesh as a ``BVHModelOBBRSS``;
- Drake: drawn as the mesh itself; in contact, the convex pieces of an approximate convex
  decomposition (CoACD, Wei et al., SIGGRAPH 2022) when the ``coacd`` package is installed,
  else the convex hull (Drake's point contact takes convex shapes only);
- mass properties: trimesh's (the closed solid's, else the convex hull's).
"""

from __future__ import annotations

import math
import multiprocessing
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from eos_svc.errors import ValidationError
from eos_svc.objects.base import (
    TINY,
    Array,
    ObjectSizeError,
    SurfaceObject,
    perpendicular_unit,
    positive,
    vector3,
)

#: a point within this distance (m) of the surface takes the nearest triangle's normal as gradient
ON_SURFACE = 1e-9
#: CoACD settings: a concavity threshold and piece count that decompose the pybullet test
#: objects in about a second each (its defaults take tens of seconds)
DECOMPOSITION = {
    "threshold": 0.15,
    "max_convex_hull": 12,
    "preprocess_mode": "off",
    "resolution": 500,
    "mcts_iterations": 40,
    "mcts_nodes": 10,
    "mcts_max_depth": 2,
    "seed": 0,
}


def load_mesh_file(file: str) -> tuple[Array, Array]:
    """(vertices (V, 3), triangles (F, 3)) of an OBJ, STL or PLY file (its units).

    Raises:
        ValidationError: ``object.file`` when the file is missing, unreadable or holds no triangles.
    """
    import trimesh

    path = Path(file)
    if path.suffix.lower() not in (".obj", ".stl", ".ply"):
        raise ObjectSizeError("file", f"must be an .obj, .stl or .ply file, got {file!r}")
    if not path.is_file():
        raise ObjectSizeError("file", f"no such file: {file!r}")
    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds on a broken file
        raise ObjectSizeError("file", f"cannot read {file!r}: {exc}") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ObjectSizeError("file", f"{file!r} holds no triangles")
    return np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64)


def winding_numbers(P: Array, triangles: Array) -> Array:
    """Generalised winding number (N,) of points ``P`` (N, 3) about the triangles (F, 3, 3):
    the sum of their signed solid angles over 4π (Van Oosterom and Strackee's formula)."""
    A = triangles[None, :, 0, :] - P[:, None, :]
    B = triangles[None, :, 1, :] - P[:, None, :]
    C = triangles[None, :, 2, :] - P[:, None, :]
    a, b, c = (np.linalg.norm(X, axis=-1) for X in (A, B, C))
    det = np.einsum("nfi,nfi->nf", A, np.cross(B, C))
    den = (
        a * b * c
        + np.einsum("nfi,nfi->nf", A, B) * c
        + np.einsum("nfi,nfi->nf", B, C) * a
        + np.einsum("nfi,nfi->nf", C, A) * b
    )
    out: Array = np.arctan2(det, den).sum(axis=1) / (2.0 * math.pi)
    return out


class Mesh(SurfaceObject):
    """A triangle mesh (``vertices`` (V, 3) in its file's units × ``scale``, ``faces`` (F, 3)),
    its centre of mass at the placement's origin."""

    kind = "mesh"
    size_fields = ("file", "vertices", "faces", "scale")
    half_size_count = 0
    orientation = "rotation"
    fittable = False
    #: a mesh's grip is judged by force closure at the contacts made, torques about its centre of
    #: mass; the 150° test of a sphere's diameter rejects grips Drake's lift test holds (docs/objects.md)
    grasp_about_diameter = False

    def __init__(
        self,
        file: str | None = None,
        scale: float = 1.0,
        vertices: Any = None,
        faces: Any = None,
        placement: pin.SE3 | None = None,
    ) -> None:
        import trimesh

        super().__init__(placement)
        self.scale = positive("scale", scale)
        if (file is None) == (vertices is None and faces is None):
            raise ObjectSizeError("file", "give either a file or vertices and faces")
        self.file = None if file is None else str(file)
        if file is not None:
            V, F = load_mesh_file(str(file))
        else:
            V, F = _arrays(vertices, faces)
        mesh = trimesh.Trimesh(V * self.scale, F, process=True)
        with np.errstate(invalid="ignore", divide="ignore"):  # a flat hull's centre of mass is 0/0
            try:
                hull = mesh.convex_hull
            except Exception:  # qhull refuses fewer than 4 points off a plane
                hull = None
            flat = hull is None or not hull.volume > 0.0
        if flat:
            raise ObjectSizeError("vertices", "the mesh is flat: its convex hull has no volume")
        self.closed = bool(mesh.is_watertight and mesh.is_volume)
        #: closed and convex (the convex hull of touches): inside is inside every face's plane
        self.convex = bool(self.closed and mesh.is_convex)
        solid = mesh if self.closed else hull
        com = np.asarray(solid.center_mass, dtype=float)
        mesh.apply_translation(-com)
        hull.apply_translation(-com)
        self.mesh, self.hull, self._solid = mesh, hull, (mesh if self.closed else hull)
        self._inline = None if file is not None else (V.tolist(), F.tolist())
        self._triangles = np.asarray(mesh.triangles, dtype=float)
        self._face_normals = outward_normals(mesh)
        self._hull_normals = np.asarray(hull.face_normals, dtype=float)
        self._hull_offsets = np.einsum("fi,fi->f", self._hull_normals, np.asarray(hull.triangles)[:, 0, :])
        self._geom = coal.BVHModelOBBRSS()
        self._geom.beginModel(len(mesh.faces), len(mesh.vertices))
        self._geom.addVertices(np.asarray(mesh.vertices, dtype=float))
        self._geom.addTriangles(np.asarray(mesh.faces, dtype=np.int64))
        self._geom.endModel()
        self._point = coal.Sphere(1e-12)
        self._req = coal.DistanceRequest()
        self._req.enable_signed_distance = True

    # -- JSON form ------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, data: Mapping[str, Any], prefix: str = "object") -> SurfaceObject:
        """The mesh of ``{"shape": "mesh", "file" | "vertices" + "faces", "scale", "position", "rpy"}``."""
        allowed = {"shape", "position", "rpy", *cls.size_fields}
        for key in data:
            if key not in allowed:
                raise ValidationError(
                    f"{prefix}.{key}", f"not a field of a mesh (takes {', '.join(sorted(allowed))})"
                )
        position = vector3(f"{prefix}.position", data.get("position", (0.0, 0.0, 0.0)))
        rpy = vector3(f"{prefix}.rpy", data.get("rpy", (0.0, 0.0, 0.0)))
        try:
            return cls(
                data.get("file"),
                data.get("scale", 1.0),
                data.get("vertices"),
                data.get("faces"),
                pin.SE3(pin.rpy.rpyToMatrix(*rpy), position),
            )
        except ObjectSizeError as exc:
            raise ObjectSizeError(f"{prefix}.{exc.field}", exc.reason) from None

    def sizes(self) -> dict[str, Any]:
        if self._inline is None:
            return {"file": self.file, "scale": self.scale}
        return {"vertices": self._inline[0], "faces": self._inline[1], "scale": self.scale}

    @property
    def half_sizes(self) -> Array:
        return np.zeros(0)

    @classmethod
    def from_half_sizes(cls, half: Array, placement: pin.SE3 | None = None) -> Mesh:
        raise TypeError("a mesh has no half sizes: it is not fitted")

    # -- distance -------------------------------------------------------------------------
    @staticmethod
    def local_distance(P: Array, half: Array) -> tuple[Array, Array]:
        raise TypeError("a mesh has no half sizes: use Mesh.local_distances")

    def nearest(self, p: Array) -> tuple[Array, float, int]:
        """(nearest surface point (local), distance ≥ 0 (m), triangle index) of local point ``p``."""
        res = coal.DistanceResult()
        tf = coal.Transform3s(np.eye(3), np.asarray(p, dtype=float))
        coal.distance(self._geom, coal.Transform3s(), self._point, tf, self._req, res)
        return np.array(res.getNearestPoint1()), abs(float(res.min_distance)), int(res.b1)

    def local_distances(self, P: Array) -> tuple[Array, Array]:
        """Signed distance (N,) and outward gradient (N, 3) at local points ``P`` (N, 3) (see the
        module doc)."""
        P = np.asarray(P, dtype=float).reshape(-1, 3)
        d, g = np.empty(len(P)), np.empty((len(P), 3))
        if self.convex:  # inside every face's plane
            inside = (P @ self._hull_normals.T - self._hull_offsets).max(axis=1) < 0.0
        else:
            inside = winding_numbers(P, self._triangles) > 0.5
        for i, p in enumerate(P):
            s, dist, face = self.nearest(p)
            sign = -1.0 if inside[i] else 1.0
            away = p - s
            n = float(np.linalg.norm(away))
            d[i] = sign * dist
            g[i] = sign * away / n if n > ON_SURFACE else self._face_normals[face]
        return d, g

    def _normal_local(self, s: Array) -> Array:
        return self._face_normals[self.nearest(s)[2]].copy()

    def _shape_matrix_local(self, s: Array, n: Array) -> Array:
        return np.zeros((3, 3))

    # -- extents --------------------------------------------------------------------------
    @property
    def geometry(self) -> coal.ShapeBase:
        return self._geom

    @property
    def diameter(self) -> float:
        return 2.0 * float(np.linalg.norm(self.hull.vertices, axis=1).max())

    def local_half_extent(self, direction: Array) -> float:
        """Where the ray from the centre leaves the convex hull (m)."""
        along = self._hull_normals @ np.asarray(direction, dtype=float)
        ahead = along > TINY
        return float(np.min(self._hull_offsets[ahead] / along[ahead]))

    def local_bounds(self, R: Array) -> Array:
        out: Array = np.abs(np.asarray(self.hull.vertices) @ R.T).max(axis=0)
        return out

    def depth_below_centre(self) -> float:
        """The lowest hull vertex's depth below the centre of mass (world −z, m)."""
        return float(-(np.asarray(self.hull.vertices) @ self.rotation.T)[:, 2].min())

    def principal_axes(self) -> Array:
        """The solid's principal axes of inertia (columns, object frame), least inertia first."""
        _, V = np.linalg.eigh(self.unit_inertia())
        return V

    def closing_axes(self) -> list[tuple[str, Array]]:
        """Across each principal axis of inertia, the thinnest first (a box's rule on the mesh)."""
        A = self.rotation @ self.principal_axes()
        V = np.asarray(self.hull.vertices) @ self.principal_axes()
        order = np.argsort(V.max(axis=0) - V.min(axis=0))
        return [(f"across principal axis {int(i) + 1}", A[:, int(i)]) for i in order]

    def approach_options(self, closing: Array) -> list[Array | None]:
        A = self.rotation @ self.principal_axes()
        return [perpendicular_unit(sign * A[:, i], closing) for i in range(3) for sign in (1.0, -1.0)]

    # -- Drake and mass -------------------------------------------------------------------
    def drake_shape(self) -> Any:
        """The mesh itself (drawing; Drake's point contact would take its convex hull)."""
        from pydrake.geometry import Mesh as DrakeMesh

        return DrakeMesh(_in_memory(self.mesh.vertices, self.mesh.faces, "mesh"))

    def convex_pieces(self) -> list[tuple[Array, Array]]:
        """The convex pieces (vertices, faces) Drake's contact takes: CoACD's decomposition when
        ``coacd`` is installed, else — or when CoACD fails on the mesh — the convex hull alone.
        CoACD runs in a forked child process: it can crash on some meshes (a segmentation fault
        in CoACD 1.0.14 on pybullet's random object 515), which must not take the caller down."""
        hull = [(np.asarray(self.hull.vertices), np.asarray(self.hull.faces))]
        try:
            import coacd  # noqa: F401 -- installed? (the child imports it again)
        except ImportError:
            return hull
        context = multiprocessing.get_context("fork")
        receiver, sender = context.Pipe(duplex=False)
        child = context.Process(
            target=_decompose, args=(np.asarray(self.mesh.vertices), np.asarray(self.mesh.faces), sender)
        )
        child.start()
        sender.close()
        try:
            pieces: list[tuple[Array, Array]] = receiver.recv()
        except EOFError:  # the child died without an answer
            pieces = hull
        child.join()
        return pieces or hull

    def triangles(self) -> Array | None:
        return self._triangles.copy()

    def drake_collision_shapes(self) -> list[Any]:
        from pydrake.geometry import Convex

        return [Convex(_in_memory(v, f, f"piece{i}")) for i, (v, f) in enumerate(self.convex_pieces())]

    @property
    def volume(self) -> float:
        return float(self._solid.volume)

    def unit_inertia(self) -> Array:
        """trimesh's inertia of the solid (unit density) about its centre of mass, over its mass."""
        out: Array = np.asarray(self._solid.moment_inertia, dtype=float) / float(self._solid.mass)
        return out


def outward_normals(mesh: Any) -> Array:
    """Unit normals (F, 3) of a trimesh's faces; a degenerate (zero-area) face, which has none —
    a hull of touches rounded to µm can hold a few — takes the direction from the centre of
    mass (the origin) to its centroid, outward on a star-shaped mesh."""
    normals = np.array(mesh.face_normals, dtype=float)
    none = np.linalg.norm(normals, axis=1) < 0.5
    if np.any(none):
        centroids = np.asarray(mesh.triangles_center, dtype=float)[none]
        lengths = np.linalg.norm(centroids, axis=1, keepdims=True)
        normals[none] = np.where(lengths > TINY, centroids / np.maximum(lengths, TINY), [0.0, 0.0, 1.0])
    return normals


def _decompose(vertices: Array, faces: Array, sender: Any) -> None:
    """CoACD's convex pieces of the mesh, sent through ``sender`` (a forked child's work)."""
    import coacd

    coacd.set_log_level("error")
    mesh = coacd.Mesh(np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int32))
    sender.send([(np.asarray(v), np.asarray(f)) for v, f in coacd.run_coacd(mesh, **DECOMPOSITION)])
    sender.close()


def _arrays(vertices: Any, faces: Any) -> tuple[Array, Array]:
    """Inline vertices (V, 3) and triangles (F, 3), checked (errors name the field)."""
    try:
        V = np.asarray(vertices, dtype=float)
    except (TypeError, ValueError):
        raise ObjectSizeError("vertices", "must be a list of [x, y, z] numbers") from None
    if V.ndim != 2 or V.shape[1] != 3 or len(V) < 4 or not np.isfinite(V).all():
        raise ObjectSizeError("vertices", f"must be at least 4 finite [x, y, z], got shape {V.shape}")
    try:
        F = np.asarray(faces)
    except (TypeError, ValueError):
        raise ObjectSizeError("faces", "must be a list of [i, j, k] vertex indices") from None
    if F.ndim != 2 or F.shape[1] != 3 or len(F) < 4 or F.dtype.kind not in "iu":
        raise ObjectSizeError("faces", f"must be at least 4 integer [i, j, k], got shape {F.shape}")
    if F.min() < 0 or F.max() >= len(V):
        raise ObjectSizeError("faces", f"vertex indices must be in [0, {len(V) - 1}]")
    return V, F.astype(np.int64)


def _in_memory(vertices: Any, faces: Any, name: str) -> Any:
    """A pydrake ``InMemoryMesh`` holding the triangles as OBJ text."""
    from pydrake.common import MemoryFile
    from pydrake.geometry import InMemoryMesh

    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in np.asarray(vertices, dtype=float)]
    lines += [f"f {i + 1} {j + 1} {k + 1}" for i, j, k in np.asarray(faces, dtype=np.int64)]
    return InMemoryMesh(mesh_file=MemoryFile("\n".join(lines) + "\n", ".obj", f"{name}.obj"))
