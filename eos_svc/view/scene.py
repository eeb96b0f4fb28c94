"""What a plan's 3-D view draws in Drake's MeshCat (world frame, z up, m): the hand, the object,
the postulated object, the contacts (``docs/view.md``, "What is drawn"); its colours also paint
the PNG pictures (:mod:`eos_svc.view.picture`).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import coal
import numpy as np
from pydrake.geometry import (
    Box,
    Capsule,
    Cylinder,
    Ellipsoid,
    Meshcat,
    MeshcatAnimation,
    MeshcatCone,
    MeshcatParams,
    Rgba,
    Shape,
    Sphere,
)
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix

from eos_svc import objects
from eos_svc.kinematics import HandModel
from eos_svc.schema.request import DEFAULT_FRICTION, ObjectSpec
from eos_svc.validation.simulation import vec

#: root of everything this package draws in a MeshCat scene
ROOT = "/eos"
HAND = f"{ROOT}/hand"
OBJECT = f"{ROOT}/object"
POSTULATE = f"{ROOT}/postulate"
CONTACTS = f"{ROOT}/contacts"

#: colours, shared with the PNG pictures (:mod:`eos_svc.view.picture`); tips in finger order
OBJECT_COLOUR = "#4c9be8"
LINK_COLOUR = "#9a9a9a"
PALM_COLOUR = "#6d6d6d"
TIP_COLOURS = ("#e8a33c", "#58b85c", "#b565c9", "#e377c2", "#17becf")
CONTACT_COLOUR = "#d62728"


def rgba(colour: str, alpha: float = 1.0) -> Rgba:
    """MeshCat's colour of ``#rrggbb`` with opacity ``alpha``."""
    r, g, b = (int(colour[i : i + 2], 16) / 255.0 for i in (1, 3, 5))
    return Rgba(r, g, b, alpha)


OBJECT_RGBA = rgba(OBJECT_COLOUR, 0.45)
POSTULATE_RGBA = Rgba(1.0, 0.85, 0.1, 0.2)
#: the postulated object is drawn this much larger (:func:`drawn_postulate`)
POSTULATE_INFLATION = 1.01
CONTACT_RGBA = rgba(CONTACT_COLOUR)
CONE_RGBA = rgba(CONTACT_COLOUR, 0.35)
#: drawn size of a contact: dot radius, normal line length, friction cone height (m)
CONTACT_DOT = 0.0025
NORMAL_LENGTH = 0.03
CONE_HEIGHT = 0.02


def new_meshcat(host: str = "localhost", port: int | None = None) -> Meshcat:
    """A MeshCat server without its stats plot, grid, axes or log line; ``port`` None: the first
    free one of 7000–7099, 0: an ephemeral one (for building a page only)."""
    params = MeshcatParams()
    params.host = host
    params.show_stats_plot = False
    if port is not None:
        params.port = port
    drake_log = logging.getLogger("drake")
    level = drake_log.level
    drake_log.setLevel(logging.WARNING)
    try:
        meshcat = Meshcat(params)
    finally:
        drake_log.setLevel(level)
    meshcat.SetProperty("/Grid", "visible", False)
    meshcat.SetProperty("/Axes", "visible", False)
    return meshcat


def play_once(meshcat: Meshcat, anim: MeshcatAnimation, autoplay: bool) -> None:
    """Set ``anim`` as the page's animation, played once and held at its end."""
    anim.set_autoplay(autoplay)
    anim.set_loop_mode(MeshcatAnimation.LoopMode.kLoopOnce)
    anim.set_clamp_when_finished(True)
    meshcat.SetAnimation(anim)


def object_shape(spec: ObjectSpec) -> tuple[Shape, RigidTransform]:
    """The MeshCat primitive of an object (its kind's ``drake_shape``) and its pose in the world."""
    shape = objects.make(spec.shape, spec.size, spec.position, spec.rpy).drake_shape()
    pose = RigidTransform(RollPitchYaw(*spec.rpy), vec(spec.position))
    return shape, pose


def postulated_object(shape: Mapping[str, Any] | None) -> ObjectSpec | None:
    """The object a post_shape postulate describes (its ``object`` entry, request JSON form), or
    ``None`` when it has no valid one (a plane, a size not known yet, an older postulate)."""
    if not isinstance(shape, Mapping):
        return None
    data = shape.get("object")
    if not isinstance(data, Mapping):
        return None
    try:
        return ObjectSpec.from_dict(dict(data))
    except (ValueError, TypeError):  # ValidationError is a ValueError
        return None


def drawn_postulate(spec: ObjectSpec) -> ObjectSpec:
    """The postulated object as drawn: its numeric sizes ×:data:`POSTULATE_INFLATION`, so that
    where it coincides with the true object it lies just outside it (no z-fighting)."""

    def grown(value: Any) -> Any:
        if isinstance(value, (int, float)):
            return float(value) * POSTULATE_INFLATION
        if isinstance(value, (list, tuple)) and all(isinstance(v, (int, float)) for v in value):
            return tuple(float(v) * POSTULATE_INFLATION for v in value)
        return value

    return replace(spec, size={k: grown(v) for k, v in spec.size.items()})


def _coal_shape(geometry: Any) -> tuple[Shape, RigidTransform]:
    """MeshCat primitive of a coal collision geometry and its offset in the geometry's frame."""
    if isinstance(geometry, coal.Sphere):
        return Sphere(float(geometry.radius)), RigidTransform()
    if isinstance(geometry, coal.Ellipsoid):
        return Ellipsoid(*(float(r) for r in geometry.radii)), RigidTransform()
    if isinstance(geometry, coal.Box):
        return Box(*(2.0 * float(h) for h in geometry.halfSide)), RigidTransform()
    if isinstance(geometry, coal.Capsule):
        return Capsule(float(geometry.radius), 2.0 * float(geometry.halfLength)), RigidTransform()
    if isinstance(geometry, coal.Cylinder):
        return Cylinder(float(geometry.radius), 2.0 * float(geometry.halfLength)), RigidTransform()
    geometry.computeLocalAABB()
    box = geometry.aabb_local
    lo, hi = np.asarray(box.min_, dtype=float), np.asarray(box.max_, dtype=float)
    return Box(*(hi - lo)), RigidTransform(vec(0.5 * (lo + hi)))


def hand_colours(hand: HandModel) -> list[str]:
    """The colour of every collision geometry of ``hand`` (id order): its finger's tip colour,
    the palm's, or the links'."""
    tips = {hand.tip_geometry_id(f): k for k, f in enumerate(hand.finger_names)}
    return [
        TIP_COLOURS[tips[gid] % len(TIP_COLOURS)]
        if gid in tips
        else PALM_COLOUR
        if g.name.startswith("palm")
        else LINK_COLOUR
        for gid, g in enumerate(hand.collision_model.geometryObjects)
    ]


@dataclass(frozen=True)
class HandPart:
    """One drawn hand geometry: its scene path, primitive, offset in its frame, colour."""

    path: str
    shape: Shape
    offset: RigidTransform
    rgba: Rgba


class HandDrawing:
    """The collision geometries of ``hand`` as MeshCat objects, and their poses at a configuration."""

    def __init__(self, hand: HandModel) -> None:
        self.hand = hand
        parts = []
        for g, colour in zip(hand.collision_model.geometryObjects, hand_colours(hand), strict=True):
            shape, offset = _coal_shape(g.geometry)
            parts.append(HandPart(f"{HAND}/{g.name}", shape, offset, rgba(colour)))
        self.parts: tuple[HandPart, ...] = tuple(parts)
        self._state = hand.state(hand.neutral())

    def poses(self, q: Sequence[float] | np.ndarray) -> list[RigidTransform]:
        """World pose of every part at configuration ``q`` (in :attr:`parts` order)."""
        state = self._state
        state.update(np.asarray(q, dtype=float))
        oMg = state.geometry_data.oMg
        out = []
        for gid, part in enumerate(self.parts):
            m = oMg[gid]
            pose = RigidTransform(RotationMatrix(m.rotation), m.translation)
            out.append(pose if part.offset.IsExactlyIdentity() else pose @ part.offset)
        return out

    def add_to(self, meshcat: Meshcat) -> None:
        """Create the hand's objects in ``meshcat`` (at the origin until posed)."""
        for part in self.parts:
            meshcat.SetObject(part.path, part.shape, part.rgba)

    def pose_in(self, meshcat: Meshcat, q: Sequence[float] | np.ndarray) -> None:
        """Place the hand's objects in ``meshcat`` at configuration ``q``."""
        for part, pose in zip(self.parts, self.poses(q), strict=True):
            meshcat.SetTransform(part.path, pose)


def add_object(meshcat: Meshcat, path: str, spec: ObjectSpec, rgba: Rgba) -> None:
    """Draw object ``spec`` at ``path`` (its pose on the path's transform)."""
    shape, pose = object_shape(spec)
    meshcat.SetObject(path, shape, rgba)
    meshcat.SetTransform(path, pose)


def touching_contacts(contacts: Mapping[str, Any] | None) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """``(finger, point, outward normal)`` of every touching contact of a result's ``contacts``
    (world, m; entries without a point or normal are skipped)."""
    out: list[tuple[str, np.ndarray, np.ndarray]] = []
    if not isinstance(contacts, Mapping):
        return out
    for finger, c in contacts.items():
        if not isinstance(c, Mapping) or not c.get("touching"):
            continue
        point, normal = c.get("point"), c.get("normal")
        if point is None or normal is None:
            continue
        try:
            p, n = np.asarray(point, dtype=float), np.asarray(normal, dtype=float)
        except (TypeError, ValueError):
            continue
        norm = float(np.linalg.norm(n)) if n.shape == (3,) and p.shape == (3,) else 0.0
        if not (norm > 1e-12 and np.all(np.isfinite(p))):
            continue
        out.append((str(finger), p, n / norm))
    return out


def add_contacts(meshcat: Meshcat, contacts: Mapping[str, Any] | None, friction: object) -> list[str]:
    """Draw every touching contact (dot, force line, friction cone of μ ``friction``, the
    request's default when not a positive number) under :data:`CONTACTS`; returns their paths."""
    number = isinstance(friction, (int, float)) and not isinstance(friction, bool)
    mu = float(friction) if number else math.nan  # type: ignore[arg-type]
    if not (math.isfinite(mu) and mu > 0):
        mu = DEFAULT_FRICTION
    paths = []
    for finger, point, normal in touching_contacts(contacts):
        path = f"{CONTACTS}/{finger}"
        inward = -normal
        meshcat.SetObject(f"{path}/dot", Sphere(CONTACT_DOT), CONTACT_RGBA)
        meshcat.SetTransform(f"{path}/dot", RigidTransform(vec(point)))
        meshcat.SetLine(
            f"{path}/normal",
            vec(np.column_stack([point, point + NORMAL_LENGTH * inward])),
            line_width=3.0,
            rgba=CONTACT_RGBA,
        )
        radius = mu * CONE_HEIGHT
        meshcat.SetObject(f"{path}/cone", MeshcatCone(CONE_HEIGHT, radius, radius), CONE_RGBA)
        meshcat.SetTransform(
            f"{path}/cone", RigidTransform(RotationMatrix.MakeFromOneVector(vec(inward), 2), vec(point))
        )
        paths.append(path)
    return paths


def set_camera(meshcat: Meshcat, target: Sequence[float]) -> None:
    """Look at ``target`` (world, m; the object) and the hand behind it from the left (−y),
    above (the hand approaches along +x)."""
    t = np.asarray(target, dtype=float) + np.array([-0.09, 0.0, 0.035])  # the hand, below the panel
    meshcat.SetCameraPose(t + np.array([-0.02, -0.22, 0.1]), t)
