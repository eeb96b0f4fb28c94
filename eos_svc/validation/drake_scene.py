"""The pieces of a Drake grasp scene that Drake validation
(:mod:`~eos_svc.validation.simulation`) and the Drake world (:mod:`~eos_svc.drivers.drake_plant`)
build the same way: the contact material, the object's free body and the hand's contact filters.
Each caller keeps its own contact options (point contact, or hydroelastic properties added to the
material it passes).

Reference: Drake, https://drake.mit.edu (MultibodyPlant, SceneGraph's proximity properties and
collision filters).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from pydrake.geometry import (
    AddContactMaterial,
    CollisionFilterDeclaration,
    GeometrySet,
    ProximityProperties,
    RoleAssign,
    SceneGraph,
    Shape,
)
from pydrake.math import RigidTransform
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import RigidBody, RotationalInertia, SpatialInertia

from eos_svc import objects
from eos_svc.schema.request import ObjectSpec


def vec(values: Sequence[float] | np.ndarray) -> Any:
    """A float array for pydrake (its stubs type arrays in a way numpy's stubs reject)."""
    return np.asarray(values, dtype=float)


def contact_material(friction: float, stiffness: float) -> ProximityProperties:
    """Proximity properties with Coulomb ``friction`` and a point-contact ``stiffness`` (N/m)."""
    material = ProximityProperties()
    AddContactMaterial(
        dissipation=None,
        point_stiffness=stiffness,
        friction=CoulombFriction(friction, friction),
        properties=material,
    )
    return material


def object_shapes(spec: ObjectSpec) -> tuple[list[Shape], SpatialInertia]:
    """Drake's collision shapes for ``spec`` (one for a primitive, the convex pieces of a mesh)
    and the unit-mass solid inertia about its centre (scaled later), both from the object's
    kind (:mod:`eos_svc.objects`)."""
    obj = objects.make(spec.shape, spec.size, spec.position)
    _, _, J = obj.mass_properties(mass=1.0)  # the object's own axes: placed at the origin, upright
    inertia = RotationalInertia(J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2])
    unit = SpatialInertia.MakeFromCentralInertia(1.0, vec((0.0, 0.0, 0.0)), inertia)
    return obj.drake_collision_shapes(), unit


def add_object(
    plant: MultibodyPlant, spec: ObjectSpec, mass: float, material: ProximityProperties, name: str = "object"
) -> RigidBody:
    """The object as a free body ``name`` (its own model instance) of ``mass`` kg, its collision
    shapes (:func:`object_shapes`, geometries ``name_0``, ``name_1``, ...) with ``material``."""
    shapes, unit_inertia = object_shapes(spec)
    instance = plant.AddModelInstance(name)
    body = plant.AddRigidBody(
        name, instance, SpatialInertia(mass, vec((0.0, 0.0, 0.0)), unit_inertia.get_unit_inertia())
    )
    for i, shape in enumerate(shapes):
        plant.RegisterCollisionGeometry(body, RigidTransform(), shape, f"{name}_{i}", material)
    return body


def set_hand_contact(
    plant: MultibodyPlant,
    scene_graph: SceneGraph,
    hand_bodies: Sequence[RigidBody],
    material: ProximityProperties,
    body_materials: Mapping[int, ProximityProperties] | None = None,
) -> GeometrySet:
    """Give every collision geometry of ``hand_bodies`` ``material`` (or ``body_materials``'
    entry for its body index) and filter out contact between hand bodies (the planner checks
    only hand–object distances); returns the hand's geometries. Call after ``Finalize``."""
    by_body = body_materials or {}
    source = plant.get_source_id()
    if source is None:
        raise ValueError("plant: not registered with a SceneGraph")
    for b in hand_bodies:
        properties = by_body.get(int(b.index()), material)
        for geometry in plant.GetCollisionGeometriesForBody(b):
            scene_graph.AssignRole(source, geometry, properties, RoleAssign.kReplace)
    hand_set = plant.CollectRegisteredGeometries(hand_bodies)
    scene_graph.collision_filter_manager().Apply(CollisionFilterDeclaration().ExcludeWithin(hand_set))
    return hand_set
