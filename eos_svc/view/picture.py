"""Pictures of a final grasp (``draw_result(plan(), "grasp.png")``): a 3-D view and three
orthographic views (mm) of the hand's collision geometry, the object and the contacts, each
primitive drawn as the convex hull of points on its surface.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import coal
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Polygon
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from scipy.spatial import ConvexHull, QhullError

from eos_svc.agents.planner import default_hand
from eos_svc.errors import ContractError, ValidationError
from eos_svc.grasp.postulate import make_object
from eos_svc.kinematics import HandModel
from eos_svc.schema.request import PlanRequest
from eos_svc.view.scene import CONTACT_COLOUR, OBJECT_COLOUR, hand_colours, touching_contacts

#: mesh resolution (segments around a circle)
SEGMENTS = 16
#: orthographic views: (title, horizontal axis, vertical axis, depth axis, depth sign toward viewer)
VIEWS = (
    ("top (x-y, from +z)", 0, 1, 2, 1.0),
    ("side (x-z, from -y)", 0, 2, 1, -1.0),
    ("front (y-z, from +x)", 1, 2, 0, 1.0),
)
#: contact label offsets (points), one per contact in turn, so coincident projections stay legible
LABEL_OFFSETS = ((5, 5), (5, -12), (-45, 5), (-45, -12))
MM = 1000.0  # m -> mm

Solid = tuple[str, list[np.ndarray], str, float]


def _unit_sphere() -> np.ndarray:
    """Points on the unit sphere: ``SEGMENTS`` meridians, their parallels and the poles."""
    theta = np.linspace(0.0, np.pi, SEGMENTS // 2 + 1)[1:-1]
    phi = np.linspace(0.0, 2.0 * np.pi, SEGMENTS, endpoint=False)
    ring = np.stack([np.outer(np.sin(theta), np.cos(phi)), np.outer(np.sin(theta), np.sin(phi))], axis=-1)
    z = np.repeat(np.cos(theta), SEGMENTS)[:, None]
    return np.vstack([np.hstack([ring.reshape(-1, 2), z]), [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]])


def _box(half: np.ndarray) -> np.ndarray:
    """The 8 corners of a box of half sides ``half`` about the origin."""
    return np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float) * half


def surface_points(shape: coal.ShapeBase) -> np.ndarray:
    """Points (local frame, m) on a coal primitive's surface whose convex hull is its drawing.

    Raises:
        ContractError (a TypeError): for a shape other than Sphere, Ellipsoid, Box, Cylinder, Capsule.
    """
    if isinstance(shape, coal.Sphere):
        return shape.radius * _unit_sphere()
    if isinstance(shape, coal.Ellipsoid):
        return np.asarray(shape.radii, dtype=float) * _unit_sphere()
    if isinstance(shape, coal.Box):
        return _box(np.asarray(shape.halfSide, dtype=float))
    if isinstance(shape, coal.Capsule):
        ball, h = shape.radius * _unit_sphere(), shape.halfLength
        return np.vstack([ball[ball[:, 2] >= 0.0] + [0, 0, h], ball[ball[:, 2] <= 0.0] - [0, 0, h]])
    if isinstance(shape, coal.Cylinder):
        phi = np.linspace(0.0, 2.0 * np.pi, SEGMENTS, endpoint=False)
        ring = shape.radius * np.stack([np.cos(phi), np.sin(phi)], axis=1)
        return np.vstack([np.column_stack([ring, np.full(SEGMENTS, z * shape.halfLength)]) for z in (-1, 1)])
    raise ContractError("shape", f"cannot draw a {type(shape).__name__}")


def _hull_mesh(points: np.ndarray) -> list[np.ndarray]:
    """The triangles (each (3, 3)) of the convex hull of ``points``."""
    return [points[s] for s in ConvexHull(points).simplices]


def shape_mesh(shape: coal.ShapeBase) -> list[np.ndarray]:
    """Triangles (each (3, 3), local frame, m) approximating a coal primitive's surface
    (:func:`surface_points`; the same errors)."""
    return _hull_mesh(surface_points(shape))


def bounding_box_mesh(shape: coal.CollisionGeometry) -> list[np.ndarray]:
    """The local axis-aligned bounding box of any coal geometry, as triangles."""
    shape.computeLocalAABB()
    lo, hi = np.asarray(shape.aabb_local.min_, dtype=float), np.asarray(shape.aabb_local.max_, dtype=float)
    return _hull_mesh(_box(0.5 * (hi - lo)) + 0.5 * (lo + hi))


def scene_solids(q: Any, request: PlanRequest, hand: HandModel | None = None) -> list[Solid]:
    """Every solid to draw: (name, world polygons in m, colour, alpha), object first; a hand
    geometry that is not a primitive is drawn as its local bounding box."""
    hand = hand or default_hand()
    obj = make_object(request.obj)
    placed = obj.placement
    own = obj.triangles()
    surface = shape_mesh(obj.geometry) if own is None else list(own)
    solids = [("object", [p @ placed.rotation.T + placed.translation for p in surface], OBJECT_COLOUR, 0.35)]
    state = hand.state(np.asarray(q, dtype=float))
    geometries = hand.collision_model.geometryObjects
    for gid, (g, colour) in enumerate(zip(geometries, hand_colours(hand), strict=True)):
        m = state.geometry_data.oMg[gid]
        try:
            polys = shape_mesh(g.geometry)
        except TypeError:
            polys = bounding_box_mesh(g.geometry)
        solids.append((g.name, [p @ m.rotation.T + m.translation for p in polys], colour, 0.9))
    return solids


def _draw_3d(
    fig: Figure, solids: list[Solid], touches: list, centre: np.ndarray, half: float, arrow: float
) -> None:
    ax = fig.add_subplot(2, 2, 1, projection="3d")
    # the limits first, so that the axes never autoscale: matplotlib 3.11's 3-D autoscaling
    # (axes3d ``_autoscale_axis``) warned of a float overflow now and then in the test suite
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre, strict=True):
        setter(c - half, c + half)
    ax.set_box_aspect((1, 1, 1))
    for name, polys, colour, alpha in solids:
        edge = (0.2, 0.3, 0.5, 0.15) if name == "object" else "none"
        ax.add_collection3d(
            Poly3DCollection(
                [p * MM for p in polys], facecolor=colour, edgecolor=edge, linewidth=0.3, alpha=alpha
            )
        )
    for _finger, p, n in touches:
        ax.scatter(*(p * MM), color=CONTACT_COLOUR, s=30, depthshade=False)
        ax.quiver(*(p * MM), *(-n * arrow), color=CONTACT_COLOUR, linewidth=2)
    ax.set(xlabel="x (mm)", ylabel="y (mm)", zlabel="z (mm)", title="3-D view")
    ax.view_init(elev=22, azim=-130)


def _draw_view(
    ax: Any, view: tuple, solids: list[Solid], touches: list, centre: np.ndarray, half: float, arrow: float
) -> None:
    label, h, v, d, sign = view
    for name, polys, colour, alpha in sorted(
        solids, key=lambda s: sign * float(np.mean(np.vstack(s[1])[:, d]))
    ):
        pts = np.vstack(polys)[:, [h, v]] * MM
        try:
            outline = pts[ConvexHull(pts).vertices]
        except (QhullError, ValueError):
            continue
        edge = "#1f4e79" if name == "object" else "#333333"
        ax.add_patch(
            Polygon(
                outline, closed=True, facecolor=colour, edgecolor=edge, linewidth=0.6, alpha=alpha, zorder=1
            )
        )
    for k, (finger, p, n) in enumerate(touches):
        pm, f = p * MM, -n * arrow
        arrowprops = {"arrowstyle": "-|>", "color": CONTACT_COLOUR, "lw": 1.8}
        ax.annotate(
            "", xy=(pm[h] + f[h], pm[v] + f[v]), xytext=(pm[h], pm[v]), arrowprops=arrowprops, zorder=3
        )
        ax.plot(pm[h], pm[v], "o", color=CONTACT_COLOUR, markersize=5, zorder=4)
        offset = LABEL_OFFSETS[k % len(LABEL_OFFSETS)]
        ax.annotate(finger, (pm[h], pm[v]), textcoords="offset points", xytext=offset, fontsize=8, zorder=4)
    ax.set(
        xlim=(centre[h] - half, centre[h] + half), ylim=(centre[v] - half, centre[v] + half), aspect="equal"
    )
    ax.set(xlabel=f"{'xyz'[h]} (mm)", ylabel=f"{'xyz'[v]} (mm)", title=label)
    ax.grid(True, linewidth=0.3, alpha=0.5)


def draw_grasp(
    path: str | Path,
    *,
    q: Any,
    request: PlanRequest,
    contacts: Mapping[str, Mapping[str, Any]],
    title: str = "",
    hand: HandModel | None = None,
) -> Path:
    """Draw the hand at ``q``, the request's object and the touching ``contacts`` to ``path`` (PNG)."""
    solids = scene_solids(q, request, hand)
    touches = touching_contacts(contacts)
    allpts = np.vstack([np.vstack(polys) for _, polys, _, _ in solids]) * MM
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * float(np.max(hi - lo)) * 1.05
    arrow = 0.35 * request.obj.diameter * MM
    fig = Figure(figsize=(12, 10), dpi=100)
    FigureCanvasAgg(fig)
    _draw_3d(fig, solids, touches, centre, half, arrow)
    for k, view in enumerate(VIEWS):
        _draw_view(fig.add_subplot(2, 2, k + 2), view, solids, touches, centre, half, arrow)
    if title:
        fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, format="png")
    return out


def result_title(result: Mapping[str, Any]) -> str:
    """A figure title from a plan result's JSON form."""
    truth = result.get("ground_truth", {})
    eps = result.get("epsilon")
    closure = "force closure" if result.get("force_closure") else "no force closure"
    angle = result.get("diameter_angle_deg")
    across = "" if angle is None else f", {angle:.0f}° across the centre"
    return (
        f"{truth.get('shape', 'object')} d = {1000 * truth.get('diameter', 0.0):.1f} mm, "
        f"seed {result.get('seed')}: "
        f"{result.get('status')}; grasp {'good' if result.get('good_grasp') else 'not good'}{across}\n"
        f"{closure} at μ = {result.get('friction')}, ε = {0.0 if eps is None else eps:.3f} "
        f"(Ferrari-Canny, torques / half diameter)"
    )


def draw_result(result: Any, path: str | Path, hand: HandModel | None = None) -> Path:
    """Draw a plan's final grasp from a :class:`~eos_svc.agents.PlanResult` or its JSON form
    (ValidationError when it has no final hand configuration)."""
    data = result.to_dict() if hasattr(result, "to_dict") else dict(result)
    q = data.get("q_final")
    if q is None:
        raise ValidationError(
            "q_final", "the result has no final hand configuration: the end agent never acted"
        )
    request = PlanRequest.from_dict(data["request"])
    title = result_title(data)
    return draw_grasp(path, q=q, request=request, contacts=data["contacts"], title=title, hand=hand)
