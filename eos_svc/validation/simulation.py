"""The grasp in Drake: a hand welded at its planned wrist pose, fingers squeezing, a free object.

Drake's ``MultibodyPlant`` (discrete, SAP, point contact) parses the planner's URDF; the
Drake-only adjustments are made here in code, never in the URDF (``docs/validation.md``). The
scene's builders serve the Drake world too (:mod:`eos_svc.drivers.drake_plant`). Reference:
Drake, https://drake.mit.edu (SAP: Castro et al., IEEE T-RO 2023).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from pydrake.geometry import (
    AddContactMaterial,
    Box,
    CollisionFilterDeclaration,
    GeometrySet,
    ProximityProperties,
    RoleAssign,
    SceneGraph,
)
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import (
    AddMultibodyPlant,
    CoulombFriction,
    ExternallyAppliedSpatialForce,
    MultibodyPlant,
    MultibodyPlantConfig,
)
from pydrake.multibody.tree import PdControllerGains, RigidBody, SpatialInertia, UnitInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from eos_svc import objects
from eos_svc.errors import EosError, ValidationError
from eos_svc.kinematics.hand import HandDescription
from eos_svc.schema.request import ObjectSpec

#: the physical model's defaults: object mass (kg), squeeze added to the planned finger angles
#: (rad), finger PD gains (N·m/rad, N·m·s/rad), point-contact stiffness (N/m), plant step (s)
DEFAULT_MASS = 0.1
DEFAULT_SQUEEZE = 0.05
DEFAULT_KP = 5.0
DEFAULT_KD = 0.05
DEFAULT_CONTACT_STIFFNESS = 2e4
DEFAULT_TIME_STEP = 1e-3

#: name of the object's body and model instance in the plant
OBJECT_NAME = "object"
#: the table's geometry name, side (m) and thickness (m): a slab whose top is the table's height
TABLE_NAME = "table"
TABLE_SIDE = 2.0
TABLE_THICKNESS = 0.1
#: name of the hand part made of the palm and every hand body outside the fingers
PALM_PART = "palm"


class SimulationError(EosError, RuntimeError):
    """Drake failed while building or simulating a grasp (the message says why)."""


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


def add_object(
    plant: MultibodyPlant, spec: ObjectSpec, mass: float, material: ProximityProperties
) -> RigidBody:
    """The object as a free body (:data:`OBJECT_NAME`, its own model instance) of ``mass`` kg,
    the solid's inertia, its kind's collision shapes (:mod:`eos_svc.objects`) with ``material``."""
    obj = objects.make(spec.shape, spec.size, spec.position)
    _, _, J = obj.mass_properties(mass=1.0)  # the object's own axes: placed at the origin, upright
    unit = UnitInertia(J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2])
    inertia = SpatialInertia(mass, vec((0.0, 0.0, 0.0)), unit)
    body = plant.AddRigidBody(OBJECT_NAME, plant.AddModelInstance(OBJECT_NAME), inertia)
    for i, shape in enumerate(obj.drake_collision_shapes()):
        plant.RegisterCollisionGeometry(body, RigidTransform(), shape, f"{OBJECT_NAME}_{i}", material)
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


def urdf_effort_limits(urdf: Path) -> dict[str, float]:
    """Every joint's ``<limit effort>`` (N·m or N) in a URDF file, by joint name."""
    out = {}
    for joint in ET.parse(urdf).getroot().iter("joint"):
        limit = joint.find("limit")
        if limit is not None and "effort" in limit.attrib:
            out[joint.attrib["name"]] = float(limit.attrib["effort"])
    return out


def hand_parser(plant: MultibodyPlant, package_dirs: Sequence[Path] = ()) -> Parser:
    """A Drake parser whose package map resolves ``package://example-robot-data/...`` (and any
    other package) under each of ``package_dirs`` (directories holding package folders)."""
    parser = Parser(plant)
    for directory in package_dirs:
        for package in sorted(Path(directory).iterdir()):
            if package.is_dir() and not parser.package_map().Contains(package.name):
                parser.package_map().Add(package.name, package)
    return parser


def palm_pose(
    urdf: Path,
    description: HandDescription,
    wrist_q: Sequence[float],
    package_dirs: Sequence[Path] = (),
) -> RigidTransform:
    """The palm's pose in the world for the wrist coordinates ``wrist_q`` (Drake's kinematics)."""
    plant = MultibodyPlant(0.0)
    hand_parser(plant, package_dirs).AddModels(urdf)
    plant.Finalize()
    context = plant.CreateDefaultContext()
    q = plant.GetPositions(context)
    for name, value in zip(description.wrist_joints, wrist_q, strict=True):
        q[plant.GetJointByName(name).position_start()] = value
    plant.SetPositions(context, q)
    return plant.EvalBodyPoseInWorld(context, plant.GetBodyByName(description.palm_frame))


class GraspSimulation:
    """One grasp ready to simulate: call :meth:`settle`, then :meth:`load` per direction.

    Args:
        urdf: the hand's URDF.
        description: which joints are the wrist and the fingers.
        q_final: every joint value in the planner's order (``joint_names``).
        joint_names: the joints ``q_final`` gives, in its order (default: the wrist joints, then
            each finger's joints, as hand3x3's model orders them); joints that are neither wrist
            nor finger joints (a pre-shape) are held at their value by the same PD, unsqueezed.
        package_dirs: directories of the packages the URDF's ``package://`` URIs name.
        obj: the object (shape, size, pose).
        friction: Coulomb μ of every contact.
        mass, squeeze, kp, kd, contact_stiffness, time_step: as
            :func:`~eos_svc.validation.validate_grasp`'s (kg, rad, N·m/rad, N·m·s/rad, N/m, s).
        table_height: the table's top (world z, m): a box welded to the world under it, in
            contact with the hand and the object like them (None: no table).
    """

    def __init__(
        self,
        urdf: Path,
        description: HandDescription,
        q_final: Sequence[float],
        obj: ObjectSpec,
        *,
        friction: float,
        joint_names: Sequence[str] | None = None,
        package_dirs: Sequence[Path] = (),
        mass: float = DEFAULT_MASS,
        squeeze: float = DEFAULT_SQUEEZE,
        kp: float = DEFAULT_KP,
        kd: float = DEFAULT_KD,
        contact_stiffness: float = DEFAULT_CONTACT_STIFFNESS,
        time_step: float = DEFAULT_TIME_STEP,
        table_height: float | None = None,
    ) -> None:
        wrist = description.wrist_joints
        finger_joints = [j for f in description.fingers for j in f.joints]
        names = list(joint_names) if joint_names is not None else [*wrist, *finger_joints]
        value = dict(zip(names, (float(v) for v in q_final), strict=True))  # validate_grasp checked the count
        held_joints = [j for j in names if j not in wrist]  # finger joints and the pre-shape
        efforts = urdf_effort_limits(urdf)
        self.effort_limit = min(efforts.get(j, np.inf) for j in finger_joints)
        if not np.isfinite(self.effort_limit):
            raise ValidationError("urdf", f"{urdf}: the finger joints have no effort limit")
        X_WP = palm_pose(urdf, description, [value[j] for j in wrist], package_dirs)

        builder = DiagramBuilder()
        config = MultibodyPlantConfig(
            time_step=time_step, contact_model="point", discrete_contact_approximation="sap"
        )
        plant, scene_graph = AddMultibodyPlant(config, builder)
        (hand,) = hand_parser(plant, package_dirs).AddModels(urdf)
        palm = plant.GetBodyByName(description.palm_frame)
        between = {
            plant.get_joint(j).child_body().index()
            for j in plant.GetJointIndices(hand)
            if plant.get_joint(j).name() in wrist
        } - {palm.index()}
        for name in wrist:
            plant.RemoveJoint(plant.GetJointByName(name))
        plant.WeldFrames(plant.world_frame(), palm.body_frame(), X_WP)
        for index in sorted(between):  # no geometry: only so they are not free bodies
            plant.WeldFrames(plant.world_frame(), plant.get_body(index).body_frame(), RigidTransform())
        for name in held_joints:
            joint = plant.GetJointByName(name)
            actuator = plant.AddJointActuator(f"{name}_motor", joint, efforts[name])
            actuator.set_controller_gains(PdControllerGains(p=kp, d=kd))

        material = contact_material(friction, contact_stiffness)  # point contact: hand, object, table
        body = add_object(plant, obj, mass, material)
        if table_height is not None:
            top = RigidTransform(vec((0.0, 0.0, table_height - 0.5 * TABLE_THICKNESS)))
            table = Box(TABLE_SIDE, TABLE_SIDE, TABLE_THICKNESS)
            plant.RegisterCollisionGeometry(plant.world_body(), top, table, TABLE_NAME, material)
        plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, 0.0])
        plant.Finalize()

        hand_bodies = [plant.get_body(i) for i in plant.GetBodyIndices(hand)]
        set_hand_contact(plant, scene_graph, hand_bodies, material)
        # hand parts: each finger (its bodies outboard of its first joint) and the palm (the rest)
        self._part: dict[int, str] = {int(b.index()): PALM_PART for b in hand_bodies}
        for finger in description.fingers:
            first = plant.GetJointByName(finger.joints[0]).index()
            for index in plant.GetBodiesKinematicallyAffectedBy([first]):
                self._part[int(index)] = finger.name

        self.plant = plant
        self.body = body
        self.simulator = Simulator(builder.Build())
        self.context = self.simulator.get_mutable_context()
        self._plant_context = plant.GetMyMutableContextFromRoot(self.context)
        pc = self._plant_context
        q = plant.GetPositions(pc)
        for name in held_joints:
            q[plant.GetJointByName(name).position_start()] = value[name]
        plant.SetPositions(pc, q)
        plant.SetFreeBodyPose(pc, body, RigidTransform(RollPitchYaw(vec(obj.rpy)), vec(obj.position)))
        # actuated joints in actuator order = held_joints order (added in that order); the
        # fingers squeeze, the pre-shape holds
        closing = set(finger_joints)
        target = np.array([value[j] + (squeeze if j in closing else 0.0) for j in held_joints])
        plant.get_desired_state_input_port(hand).FixValue(pc, np.concatenate([target, np.zeros(len(target))]))
        plant.get_actuation_input_port().FixValue(pc, np.zeros(plant.num_actuated_dofs()))
        self._apply(np.zeros(3))
        self.start = self.position()
        self._settled = self.context.Clone()

    def _apply(self, force: np.ndarray) -> None:
        """The external force on the object's centre of mass (N, world frame)."""
        f = ExternallyAppliedSpatialForce()
        f.body_index = self.body.index()
        f.p_BoBq_B = vec((0.0, 0.0, 0.0))
        f.F_Bq_W = SpatialForce(vec((0.0, 0.0, 0.0)), vec(force))
        self.plant.get_applied_spatial_force_input_port().FixValue(self._plant_context, [f])

    def position(self) -> np.ndarray:
        """The object's centre in the world (m)."""
        return self.body_position(OBJECT_NAME)

    def body_position(self, name: str) -> np.ndarray:
        """The origin of the plant's body ``name`` in the world now (m)."""
        body = self.plant.GetBodyByName(name)
        return np.array(self.plant.EvalBodyPoseInWorld(self._plant_context, body).translation())

    def touching(self) -> tuple[str, ...]:
        """The hand parts (palm, finger names) in contact with the object now, sorted."""
        results = self.plant.get_contact_results_output_port().Eval(self._plant_context)
        me, parts = self.body.index(), set()
        for info in (results.point_pair_contact_info(i) for i in range(results.num_point_pair_contacts())):
            a, b = info.bodyA_index(), info.bodyB_index()
            other = int(b if a == me else a) if me in (a, b) else None
            if other in self._part:
                parts.add(self._part[other])
        return tuple(sorted(parts))

    def settle(self, seconds: float) -> np.ndarray:
        """Squeeze with no load for ``seconds``; returns the object's centre after it (m)."""
        self.simulator.Initialize()
        self.simulator.AdvanceTo(self.context.get_time() + seconds)
        self._settled = self.context.Clone()
        return self.position()

    def load(
        self, direction: np.ndarray, force: float, seconds: float, sample: float, stop_distance: float
    ) -> tuple[float, float, bool]:
        """From the settled state, pull the object with ``force`` N along unit ``direction``
        for ``seconds``; sample its displacement every ``sample`` s, stop once it is
        ``stop_distance`` m away. Returns (largest displacement, final displacement, stopped early)."""
        self.context.SetTimeStateAndParametersFrom(self._settled)
        origin = self.position()
        self._apply(force * np.asarray(direction, dtype=float))
        self.simulator.Initialize()
        t0 = self.context.get_time()
        largest = final = 0.0
        steps = max(1, round(seconds / sample))
        for k in range(1, steps + 1):
            self.simulator.AdvanceTo(t0 + seconds * k / steps)
            final = float(np.linalg.norm(self.position() - origin))
            largest = max(largest, final)
            if final >= stop_distance:
                return largest, final, k < steps
        return largest, final, False
