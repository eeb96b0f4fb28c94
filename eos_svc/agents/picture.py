"""Pictures of a final grasp: the hand's collision geometry, the object, the contacts.

    from eos_svc.agents import plan
    from eos_svc.agents.picture import draw_result
    draw_result(plan(), "grasp.png")

One figure, four panels: a 3-D view and three orthographic views (top x–y, side x–z,
front y–z) in millimetres. The hand is drawn from its Pinocchio GeometryModel at the final
configuration (palm box, link cylinders, fingertip spheres, each placed by
``GeometryData.oMg``), the object from the request's primitive at its pose; every touching
contact is a red dot with an arrow along the force direction (−outward normal, into the
object). Orthographic views paint solids back to front (each convex solid's outline is the
convex hull of its projected surface mesh). Rendering uses matplotlib's Agg canvas directly
(no global backend is changed).
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

from eos_svc.agents.planner import default_hand, make_object
from eos_svc.errors import ContractError, ValidationError
from eos_svc.kinematics import HandModel
from eos_svc.schema.request import PlanRequest

#: mesh resolution (segments around a circle)
SEGMENTS = 16
#: colours
OBJECT_COLOUR = "#4c9be8"
HAND_COLOUR = "#9a9a9a"
PALM_COLOUR = "#6d6d6d"
TIP_PALETTE = ("#e8a33c", "#58b85c", "#b565c9", "#e377c2", "#17becf")
CONTACT_COLOUR = "#d62728"
#: orthographic views: (title, horizontal axis, vertical axis, depth axis, depth sign toward viewer)
VIEWS = (
    ("top (x-y, from +z)", 0, 1, 2, 1.0),
    ("side (x-z, from -y)", 0, 2, 1, -1.0),
    ("front (y-z, from +x)", 1, 2, 0, 1.0),
)
AXIS_NAMES = "xyz"
#: contact label offsets (points), one per contact in turn, so coincident projections stay legible
LABEL_OFFSETS = ((5, 5), (5, -12), (-45, 5), (-45, -12))


def _sphere_mesh(radii: np.ndarray, z_shift: float = 0.0, hemisphere: int = 0) -> list[np.ndarray]:
    """Quads of a (possibly scaled) sphere; ``hemisphere`` ±1 keeps only that half (capsule)."""
    n = SEGMENTS
    lo, hi = (0.0, np.pi / 2) if hemisphere > 0 else ((np.pi / 2, np.pi) if hemisphere < 0 else (0.0, np.pi))
    theta = np.linspace(lo, hi, n // 2 + 1)
    phi = np.linspace(0.0, 2.0 * np.pi, n + 1)
    st, ct = np.sin(theta), np.cos(theta)
    grid = (
        np.stack(
            [np.outer(st, np.cos(phi)), np.outer(st, np.sin(phi)), np.outer(ct, np.ones_like(phi))], axis=-1
        )
        * radii
    )
    grid[..., 2] += z_shift
    return [
        np.array([grid[i, j], grid[i, j + 1], grid[i + 1, j + 1], grid[i + 1, j]])
        for i in range(len(theta) - 1)
        for j in range(n)
    ]


def _cylinder_mesh(radius: float, half: float, caps: bool = True) -> list[np.ndarray]:
    phi = np.linspace(0.0, 2.0 * np.pi, SEGMENTS + 1)
    ring = np.stack([radius * np.cos(phi), radius * np.sin(phi)], axis=1)
    quads = [
        np.array([[*ring[j], -half], [*ring[j + 1], -half], [*ring[j + 1], half], [*ring[j], half]])
        for j in range(SEGMENTS)
    ]
    if caps:
        for z in (-half, half):
            quads.append(np.column_stack([ring[:-1], np.full(SEGMENTS, z)]))
    return quads


def _box_mesh(half: np.ndarray) -> list[np.ndarray]:
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float) * half
    faces = [(0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5)]
    return [corners[list(f)] for f in faces]


def shape_mesh(shape: coal.ShapeBase) -> list[np.ndarray]:
    """Polygons (each (k, 3), local frame) approximating a coal primitive's surface.

    Raises:
        TypeError: for a shape other than Sphere, Ellipsoid, Box, Cylinder, Capsule.
    """
    if isinstance(shape, coal.Sphere):
        return _sphere_mesh(np.full(3, shape.radius))
    if isinstance(shape, coal.Ellipsoid):
        return _sphere_mesh(np.asarray(shape.radii, dtype=float))
    if isinstance(shape, coal.Box):
        return _box_mesh(np.asarray(shape.halfSide, dtype=float))
    if isinstance(shape, coal.Capsule):
        r, h = shape.radius, shape.halfLength
        ends = _sphere_mesh(np.full(3, r), h, 1) + _sphere_mesh(np.full(3, r), -h, -1)
        return _cylinder_mesh(r, h, caps=False) + ends
    if isinstance(shape, coal.Cylinder):
        return _cylinder_mesh(shape.radius, shape.halfLength)
    raise ContractError("shape", f"cannot draw a {type(shape).__name__}")


def _placed(polys: list[np.ndarray], rotation: np.ndarray, translation: np.ndarray) -> list[np.ndarray]:
    return [p @ rotation.T + translation for p in polys]


def scene_solids(
    q: Any, request: PlanRequest, hand: HandModel | None = None
) -> list[tuple[str, list[np.ndarray], str, float]]:
    """Every solid to draw: (name, world polygons in m, colour, alpha), object first.

    Fingertips are coloured per finger (in the hand's finger order), palms darker; a
    geometry that is not a primitive is drawn as its local bounding box.
    """
    hand = hand or default_hand()
    obj = make_object(request.obj)
    pl = obj.placement
    solids = [("object", _placed(shape_mesh(obj.geometry), pl.rotation, pl.translation), OBJECT_COLOUR, 0.35)]
    state = hand.state(np.asarray(q, dtype=float))
    tips = {hand.tip_geometry_id(f): k for k, f in enumerate(hand.finger_names)}
    for gid, g in enumerate(hand.collision_model.geometryObjects):
        m = state.geometry_data.oMg[gid]
        if gid in tips:
            colour = TIP_PALETTE[tips[gid] % len(TIP_PALETTE)]
        elif g.name.startswith("palm"):
            colour = PALM_COLOUR
        else:
            colour = HAND_COLOUR
        try:
            polys = shape_mesh(g.geometry)
        except TypeError:
            polys = _aabb_mesh(g.geometry)
        solids.append((g.name, _placed(polys, m.rotation, m.translation), colour, 0.9))
    return solids


def _aabb_mesh(shape: coal.CollisionGeometry) -> list[np.ndarray]:
    """The local axis-aligned bounding box of any coal geometry, as a box mesh."""
    shape.computeLocalAABB()
    box = shape.aabb_local
    lo, hi = np.asarray(box.min_, dtype=float), np.asarray(box.max_, dtype=float)
    return [p + 0.5 * (lo + hi) for p in _box_mesh(0.5 * (hi - lo))]


def _contacts(contacts: Mapping[str, Mapping[str, Any]]) -> list[tuple[str, np.ndarray, np.ndarray]]:
    out = []
    for finger, c in contacts.items():
        if c.get("touching"):
            out.append((finger, np.asarray(c["point"], dtype=float), np.asarray(c["normal"], dtype=float)))
    return out


def draw_grasp(
    path: str | Path,
    *,
    q: Any,
    request: PlanRequest,
    contacts: Mapping[str, Mapping[str, Any]],
    title: str = "",
    hand: HandModel | None = None,
) -> Path:
    """Draw the hand at ``q``, the request's object and the touching ``contacts`` to ``path`` (PNG).

    Returns:
        the path written.
    """
    solids = scene_solids(q, request, hand)
    touches = _contacts(contacts)
    scale = 1000.0  # m -> mm
    allpts = np.vstack([np.vstack(polys) for _, polys, _, _ in solids]) * scale
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * float(np.max(hi - lo)) * 1.05
    arrow = 0.35 * request.obj.diameter * scale

    fig = Figure(figsize=(12, 10), dpi=100)
    FigureCanvasAgg(fig)
    ax3 = fig.add_subplot(2, 2, 1, projection="3d")
    # the limits first, so that the axes never autoscale: matplotlib 3.11's 3-D autoscaling
    # (axes3d ``_autoscale_axis``) warned of a float overflow now and then in the test suite
    for setter, c in zip((ax3.set_xlim, ax3.set_ylim, ax3.set_zlim), centre, strict=True):
        setter(c - half, c + half)
    ax3.set_box_aspect((1, 1, 1))
    for name, polys, colour, alpha in solids:
        coll = Poly3DCollection(
            [p * scale for p in polys],
            facecolor=colour,
            edgecolor="none" if name != "object" else (0.2, 0.3, 0.5, 0.15),
            linewidth=0.3,
            alpha=alpha,
        )
        ax3.add_collection3d(coll)
    for _finger, p, n in touches:
        pm = p * scale
        ax3.scatter(*pm, color=CONTACT_COLOUR, s=30, depthshade=False)
        ax3.quiver(*pm, *(-n * arrow), color=CONTACT_COLOUR, linewidth=2)
    ax3.set_xlabel("x (mm)")
    ax3.set_ylabel("y (mm)")
    ax3.set_zlabel("z (mm)")
    ax3.view_init(elev=22, azim=-130)
    ax3.set_title("3-D view")

    for k, (label, h, v, d, sign) in enumerate(VIEWS):
        ax = fig.add_subplot(2, 2, k + 2)
        order = sorted(solids, key=lambda s: sign * float(np.mean(np.vstack(s[1])[:, d])))
        for name, polys, colour, alpha in order:
            pts = np.vstack(polys)[:, [h, v]] * scale
            try:
                hull = ConvexHull(pts)
            except (QhullError, ValueError):
                continue
            ax.add_patch(
                Polygon(
                    pts[hull.vertices],
                    closed=True,
                    facecolor=colour,
                    edgecolor="#333333" if name != "object" else "#1f4e79",
                    linewidth=0.6,
                    alpha=alpha,
                    zorder=1,
                )
            )
        for k_contact, (finger, p, n) in enumerate(touches):
            pm = p * scale
            f = -n * arrow
            ax.annotate(
                "",
                xy=(pm[h] + f[h], pm[v] + f[v]),
                xytext=(pm[h], pm[v]),
                arrowprops={"arrowstyle": "-|>", "color": CONTACT_COLOUR, "lw": 1.8},
                zorder=3,
            )
            ax.plot(pm[h], pm[v], "o", color=CONTACT_COLOUR, markersize=5, zorder=4)
            ax.annotate(
                finger,
                (pm[h], pm[v]),
                textcoords="offset points",
                xytext=LABEL_OFFSETS[k_contact % len(LABEL_OFFSETS)],
                fontsize=8,
                zorder=4,
            )
        ax.set_xlim(centre[h] - half, centre[h] + half)
        ax.set_ylim(centre[v] - half, centre[v] + half)
        ax.set_aspect("equal")
        ax.grid(True, linewidth=0.3, alpha=0.5)
        ax.set_xlabel(f"{AXIS_NAMES[h]} (mm)")
        ax.set_ylabel(f"{AXIS_NAMES[v]} (mm)")
        ax.set_title(label)
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
    """Draw a plan's final grasp from a :class:`~eos_svc.agents.PlanResult` or its JSON form.

    Raises:
        ValueError: the result holds no final hand configuration (the end agent never
            judged the grasp, or the trace was not kept).
    """
    data = result.to_dict() if hasattr(result, "to_dict") else dict(result)
    q = data.get("q_final")
    if q is None:
        raise ValidationError(
            "q_final", "the result has no final hand configuration: the end agent never acted"
        )
    request = PlanRequest.from_dict(data["request"])
    title = result_title(data)
    return draw_grasp(path, q=q, request=request, contacts=data["contacts"], title=title, hand=hand)
