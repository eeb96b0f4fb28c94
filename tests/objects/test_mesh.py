"""The mesh kind against closed forms: a box's triangle mesh measured as the box primitive is
(signed distance, gradient, extents, mass), read from OBJ, STL and PLY files and inline, and its
errors naming the field."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
import trimesh

from eos_svc.errors import ValidationError
from eos_svc.grasp.postulate import make_object
from eos_svc.objects import FITTED_KINDS, KINDS, Box, Mesh, ObjectSizeError
from eos_svc.schema.request import MAX_MESH_VERTICES, MESH, MESH_FIELDS, SHAPE_SIZE_FIELDS, ObjectSpec
from eos_svc.shape.hull import APPROXIMATE_CAP, hull_postulate
from eos_svc.shape.touches import Touches

SIZE = np.array([0.05, 0.04, 0.03])
PLACEMENT = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.2, 0.7), np.array([0.2, 0.01, -0.02]))


def box_mesh() -> trimesh.Trimesh:
    return trimesh.creation.box(extents=SIZE)


def inline(mesh: trimesh.Trimesh) -> dict:
    return {"vertices": mesh.vertices.tolist(), "faces": mesh.faces.tolist()}


def test_a_box_mesh_measures_as_the_box_primitive():
    mesh = Mesh(**inline(box_mesh()), placement=PLACEMENT)
    box = Box(SIZE, PLACEMENT)
    rng = np.random.default_rng(3)
    P = PLACEMENT.translation + rng.normal(scale=0.03, size=(300, 3))
    d_mesh, g_mesh = mesh.signed_distances(P)
    d_box, g_box = box.signed_distances(P)
    assert np.abs(d_mesh - d_box).max() < 1e-9
    away = np.abs(d_box) > 1e-4  # off the medial surfaces, where both gradients are unique
    inside_face = (d_box < 0) & (np.sort(np.abs(np.abs(box.to_local(P)) - SIZE / 2), axis=1)[:, 1] > 1e-3)
    keep = away & ((d_box > 0) | inside_face)
    assert np.abs(g_mesh[keep] - g_box[keep]).max() < 1e-6
    assert np.allclose(mesh.half_extents(), box.half_extents(), atol=1e-12)
    assert mesh.diameter == pytest.approx(box.diameter)
    assert mesh.volume == pytest.approx(float(np.prod(SIZE)))
    mass, c, J = mesh.mass_properties(mass=0.1)
    _, c_box, J_box = box.mass_properties(mass=0.1)
    assert mass == 0.1 and np.allclose(c, c_box) and np.allclose(J, J_box, atol=1e-12)


def test_the_signed_distance_gradient_is_the_finite_difference():
    mesh = Mesh(**inline(trimesh.creation.icosphere(subdivisions=2, radius=0.03)), placement=PLACEMENT)
    rng = np.random.default_rng(5)
    h = 1e-7
    for p in PLACEMENT.translation + rng.normal(scale=0.03, size=(20, 3)):
        g = mesh.signed_distances(p[None])[1][0]
        fd = [
            (mesh.signed_distance(p + h * e) - mesh.signed_distance(p - h * e)) / (2 * h) for e in np.eye(3)
        ]
        assert np.allclose(g, fd, atol=1e-5)


def test_the_centre_of_mass_is_the_origin_and_position_places_it():
    shifted = box_mesh()
    shifted.apply_translation([0.3, -0.1, 0.05])  # the file's origin is not its centre of mass
    spec = ObjectSpec("mesh", inline(shifted), (0.2, 0.0, 0.0))
    obj = make_object(spec)
    assert np.allclose(obj.centre, [0.2, 0.0, 0.0])
    assert obj.signed_distance(np.array([0.2, 0.0, 0.0])) == pytest.approx(-0.015)


@pytest.mark.parametrize("suffix", [".obj", ".stl", ".ply"])
def test_files_are_read_and_scaled(tmp_path, suffix):
    path = tmp_path / f"box{suffix}"
    box = box_mesh()
    box.apply_scale(1000.0)  # millimetres
    box.export(path)
    obj = make_object(ObjectSpec("mesh", {"file": str(path), "scale": 0.001}, (0.2, 0.0, 0.0)))
    assert np.allclose(2.0 * obj.half_extents(), SIZE)
    assert obj.to_dict()["file"] == str(path)


def test_inline_json_round_trips():
    spec = ObjectSpec.from_dict(
        {"shape": "mesh", **inline(box_mesh()), "scale": 2.0, "position": [0.2, 0, 0]}
    )
    assert ObjectSpec.from_dict(spec.to_dict()) == spec
    assert np.allclose(2.0 * make_object(spec).half_extents(), 2.0 * SIZE)


@pytest.mark.parametrize(
    ("fields", "where"),
    [
        ({"file": "nowhere.obj"}, "object.file"),
        ({"file": "mesh.step"}, "object.file"),
        ({"vertices": [[0, 0, 0]] * (MAX_MESH_VERTICES + 1), "faces": [[0, 1, 2]] * 4}, "object.vertices"),
        (
            {"vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], "faces": [[0, 1, 9]] * 4},
            "object.faces[0][2]",
        ),
        (
            {"vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], "faces": [[0, 1, 2]] * 4},
            "object.vertices",
        ),
        ({"file": "a.obj", "vertices": [[0, 0, 0]] * 4, "faces": [[0, 1, 2]] * 4}, "object.file"),
        ({"vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]}, "object.faces"),
    ],
)
def test_bad_meshes_name_the_field(fields, where):
    with pytest.raises(ValidationError) as err:
        make_object(ObjectSpec("mesh", {"scale": 0.01, **fields}, (0.2, 0.0, 0.0)))
    assert err.value.field == where


def test_a_flat_mesh_is_refused_by_the_kind():
    with pytest.raises(ObjectSizeError, match="flat"):
        Mesh(
            vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]],
            faces=[[0, 1, 2], [1, 3, 2], [0, 2, 1], [1, 2, 3]],
        )


def test_drake_takes_the_convex_pieces():
    obj = Mesh(**inline(box_mesh()))
    pieces = obj.convex_pieces()
    assert sum(trimesh.Trimesh(v, f).convex_hull.volume for v, f in pieces) == pytest.approx(
        obj.volume, rel=0.05
    )
    assert len(obj.drake_collision_shapes()) == len(pieces)


def test_the_hull_of_touches_on_a_box_is_the_box_with_a_capped_confidence():
    rng = np.random.default_rng(1)
    half = SIZE / 2
    axis, sign = rng.integers(0, 3, 400), rng.choice([-1.0, 1.0], 400)
    surface = rng.uniform(-half, half, size=(400, 3))
    surface[np.arange(400), axis] = sign * half[axis]
    normals = np.zeros((400, 3))
    normals[np.arange(400), axis] = sign
    r = 0.01
    touches = Touches(surface + r * normals, normals, np.full(len(surface), r))
    hull = hull_postulate(touches)
    assert hull is not None
    obj = make_object(ObjectSpec.from_dict(hull.object))
    assert obj.volume == pytest.approx(float(np.prod(SIZE)), rel=0.05)
    assert np.allclose(obj.centre, 0.0, atol=1e-3)
    assert hull.confidence == pytest.approx(APPROXIMATE_CAP)
    # touches inside a concavity (under the hull) lower it
    inner = Touches(
        np.vstack([touches.centres, [[0.0, 0.0, r]]]),
        np.vstack([touches.normals, [[0.0, 0.0, 1.0]]]),
        np.full(len(surface) + 1, r),
    )
    assert hull_postulate(inner).confidence < APPROXIMATE_CAP  # type: ignore[union-attr]
    # on a table, the touches' shadows close the bottom
    top_only = Touches(touches.centres[surface[:, 2] > 0], touches.normals[surface[:, 2] > 0], r)
    tabled = hull_postulate(top_only, table_height=-0.015)
    assert tabled is not None
    assert make_object(ObjectSpec.from_dict(tabled.object)).volume == pytest.approx(
        float(np.prod(SIZE)), rel=0.1
    )
    assert math.isclose(tabled.centre[2], 0.0, abs_tol=2e-3)


def test_the_request_schema_lists_the_registry_kinds_fields():
    """The schema stays free of coal and Pinocchio (the clients import it): its size fields are
    the registry's, kind by kind."""
    assert {k: c.size_fields for k, c in FITTED_KINDS.items()} == SHAPE_SIZE_FIELDS
    assert Mesh.size_fields == MESH_FIELDS and set(KINDS) == {*SHAPE_SIZE_FIELDS, MESH}


def test_a_mesh_is_drawn_from_its_triangles(tmp_path):
    from eos_svc.agents.planner import default_hand
    from eos_svc.schema.request import PlanRequest
    from eos_svc.view.picture import scene_solids

    spec = ObjectSpec("mesh", inline(box_mesh()), (0.21, 0.02, 0.0))
    solids = scene_solids(default_hand().neutral(), PlanRequest(obj=spec))
    assert solids[0][0] == "object" and len(solids[0][1]) == 12


def test_a_degenerate_face_gets_an_outward_normal():
    # a hull of touches rounded to µm can hold zero-area faces (pybullet random 629): their normal
    # was the zero vector, and a fingertip landing on one broke the grasp's ε
    box = box_mesh()
    V = np.vstack([box.vertices, 0.5 * (box.vertices[0] + box.vertices[1])])  # a point on an edge
    F = np.vstack([box.faces, [[0, 1, len(V) - 1]]])  # collinear: zero area
    mesh = Mesh(vertices=V.tolist(), faces=F.tolist())
    assert np.allclose(np.linalg.norm(mesh._face_normals, axis=1), 1.0)
    degenerate = int(np.argmin(mesh.mesh.area_faces))
    assert mesh.mesh.area_faces[degenerate] < 1e-15
    centroid = mesh.mesh.triangles_center[degenerate]
    assert float(mesh._face_normals[degenerate] @ centroid) > 0.0  # outward
