"""The Drake world's plant: the whole hand on its wrist joints, a table, the object resting on it.

Built with Drake's ``MultibodyPlant`` (discrete, SAP, point contact) from the URDF the planner
loads with Pinocchio (parsed by Drake's own ``Parser``). Drake-only choices, made here in code:

- every joint gets an actuator with an implicit PD controller (``PdControllerGains``) capped by
  the URDF's effort limit: the wrist's joints stiff (position control), the finger joints soft
  (``finger_kp``; Drake validation's gains);
- the hand's own weight is off (a robot arm carries it); the object's is on (gravity, its mass);
- a table, a box welded to the world, its top at the object's lowest point, so the object rests
  on it; the hand does not collide with the table (the planner plans no table avoidance) nor
  with itself; every hand, table and object geometry has the request's Coulomb μ.

Reference: Drake, https://drake.mit.edu (MultibodyPlant; SAP: Castro et al., "An Unconstrained
Convex Formulation of Compliant Contact", IEEE T-RO 2023).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from pydrake.geometry import (
    AddCompliantHydroelasticProperties,
    AddCompliantHydroelasticPropertiesForHalfSpace,
    AddRigidHydroelasticProperties,
    CollisionFilterDeclaration,
    GeometrySet,
    HalfSpace,
)
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import PdControllerGains
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from eos_svc.kinematics import HandModel
from eos_svc.objects import SurfaceObject
from eos_svc.schema.request import ObjectSpec
from eos_svc.validation.drake_hand import drake_urdf
from eos_svc.validation.simulation import (
    add_object,
    contact_material,
    hand_parser,
    set_hand_contact,
    urdf_effort_limits,
    vec,
)

#: the object starts this far above the table, m
DROP = 1e-4
#: below this spin about horizontal axes (rad/s) the object is not rolling: no rolling torque
STILL_SPIN = 1e-6
#: the table's normal out of the object
DOWN = np.array([0.0, 0.0, -1.0])


@dataclass(frozen=True)
class PlantSettings:
    """The physical model's constants (SI).

    Attributes:
        mass: the object's mass, kg.
        time_step: the discrete plant's step, s.
        wrist_kp, wrist_kd: the wrist's translation joints' PD gains (N/m, N·s/m).
        wrist_rot_kp, wrist_rot_kd: the wrist's rotation joints' gains (N·m/rad, N·m·s/rad).
        finger_kp, finger_kd: the finger joints' gains (N·m/rad, N·m·s/rad), unless the hand's
            description gives its own (``[drake]`` kp, kd; N/m, N·s/m for a prismatic finger).
        contact_stiffness: point-contact stiffness, N/m.
        table_slab, table_modulus: the table's compliant layer (hydroelastic): thickness (m) and
            modulus (Pa).
        resolution: the object's hydroelastic mesh resolution (m; at most a tenth of its
            diameter, at least 3 mm).
        rolling_resistance: the table's rolling resistance coefficient (a torque ``c N h``
            against rolling: neither point nor hydroelastic contact has one, and a ball touched
            once would roll on for ever); rolling_update: how often its torque is updated, s.
        soft_tips, tip_modulus, tip_resolution: the fingertips as compliant hydroelastic bodies
            (a pressure patch with torsional friction, as a soft pad has), their modulus (Pa) and
            mesh resolution (m); without them, point contact.
        hand_touches_table: whether the hand collides with the table (off by default: the
            planner plans no table avoidance and EP1 feels a resting object's bottom, which a
            table would hide).
    """

    mass: float = 0.1
    time_step: float = 1e-3
    wrist_kp: float = 4000.0
    wrist_kd: float = 80.0
    wrist_rot_kp: float = 100.0
    wrist_rot_kd: float = 2.0
    finger_kp: float = 5.0
    finger_kd: float = 0.05
    contact_stiffness: float = 2e4
    table_slab: float = 0.01
    table_modulus: float = 1e7
    resolution: float = 0.01
    rolling_resistance: float = 0.01
    rolling_update: float = 0.005
    soft_tips: bool = True
    tip_modulus: float = 1e6
    tip_resolution: float = 0.008
    hand_touches_table: bool = False


class DrakeHandPlant:
    """The hand, the table and the object in one Drake simulation (see the module docstring).

    Joint values cross in the planner's order (:attr:`HandModel.lower`'s: wrist then fingers).
    """

    def __init__(
        self,
        hand: HandModel,
        spec: ObjectSpec,
        obj: SurfaceObject,
        friction: float,
        settings: PlantSettings | None = None,
        table_height: float | None = None,
    ) -> None:
        s = settings or PlantSettings()
        self.settings = s
        builder = DiagramBuilder()
        config = MultibodyPlantConfig(
            time_step=s.time_step,
            contact_model="hydroelastic_with_fallback",
            discrete_contact_approximation="sap",
        )
        plant, scene_graph = AddMultibodyPlant(config, builder)
        # the URDF the hand's description makes (a composite for a described hand), as Drake
        # validation reads it (drake_urdf raises ValidationError for a hand without one)
        with drake_urdf(hand) as (urdf, package_dirs):
            efforts = urdf_effort_limits(urdf)
            (model,) = hand_parser(plant, package_dirs).AddModels(urdf)
        names = [str(n) for n in hand.model.names[1:]]  # Pinocchio's joints in q order (1 DoF each)
        wrist = set(hand.description.wrist_joints)
        drake = dict(getattr(hand, "drake", {}))
        for name in names:
            joint = plant.GetJointByName(name, model)
            if name in wrist:
                prismatic = joint.type_name() == "prismatic"
                kp, kd = (s.wrist_kp, s.wrist_kd) if prismatic else (s.wrist_rot_kp, s.wrist_rot_kd)
            else:  # the description's [drake] gains (as Drake validation's), else the settings'
                kp, kd = drake.get("kp", s.finger_kp), drake.get("kd", s.finger_kd)
            actuator = plant.AddJointActuator(f"{name}_motor", joint, efforts.get(name, np.inf))
            actuator.set_controller_gains(PdControllerGains(p=kp, d=kd))
        material = contact_material(friction, s.contact_stiffness)
        lowest = float(obj.centre[2] - obj.half_extent(np.array([0.0, 0.0, 1.0])))
        lowest = lowest if table_height is None else float(table_height)  # the request's table
        # the table: a soft half-space (hydroelastic) with its top at z = lowest, so that the object
        # rests on a pressure patch, not on one point (a box on a box balances on its deepest point)
        table_material = contact_material(friction, s.contact_stiffness)
        AddCompliantHydroelasticPropertiesForHalfSpace(s.table_slab, s.table_modulus, table_material)
        table = plant.RegisterCollisionGeometry(
            plant.world_body(), RigidTransform(vec((0.0, 0.0, lowest))), HalfSpace(), "table", table_material
        )
        object_material = contact_material(friction, s.contact_stiffness)
        resolution = min(s.resolution, max(0.003, 0.1 * float(obj.diameter)))  # a sagitta < 0.2 mm
        AddRigidHydroelasticProperties(resolution, object_material)
        body = add_object(plant, spec, s.mass, object_material)  # a mesh: its convex pieces
        plant.set_gravity_enabled(model, False)
        plant.Finalize()
        hand_bodies = [plant.get_body(i) for i in plant.GetBodyIndices(model)]
        tips = {int(plant.GetFrameByName(hand.model.frames[hand.tip_frame_id(f)].name, model).body().index())
                for f in hand.finger_names}  # fmt: skip
        tip_material = contact_material(friction, s.contact_stiffness)  # soft pads: torsional friction
        AddCompliantHydroelasticProperties(s.tip_resolution, s.tip_modulus, tip_material)
        tip_materials = dict.fromkeys(tips, tip_material) if s.soft_tips else {}  # the rest: point contact
        hand_set = set_hand_contact(plant, scene_graph, hand_bodies, material, tip_materials)
        if not s.hand_touches_table:
            scene_graph.collision_filter_manager().Apply(
                CollisionFilterDeclaration().ExcludeBetween(hand_set, GeometrySet(table))
            )
        self.plant, self.model, self.body = plant, model, body
        self.tip_bodies = {
            f: plant.GetFrameByName(hand.model.frames[hand.tip_frame_id(f)].name, model).body()
            for f in hand.finger_names
        }
        self._inspector = scene_graph.model_inspector()
        self.diagram = builder.Build()
        self.simulator = Simulator(self.diagram)
        self.root = self.simulator.get_mutable_context()
        self.context = plant.GetMyMutableContextFromRoot(self.root)
        # q order: Drake's position index of each planner joint (the actuators were added in it)
        self._index = [plant.GetJointByName(n, model).position_start() for n in names]
        self.table_top = lowest
        # dropped from 0.1 mm above the table (a vertex exactly on its plane is degenerate for the
        # hydroelastic intersection)
        pose = RigidTransform(RollPitchYaw(vec(spec.rpy)), vec(obj.centre) + vec((0.0, 0.0, DROP)))
        plant.SetFreeBodyPose(self.context, body, pose)
        plant.get_actuation_input_port().FixValue(self.context, np.zeros(plant.num_actuated_dofs()))
        self._n = len(names)
        self._table_geometry = table
        self._wrench = (np.zeros(3), np.zeros(3))
        self._bodies: dict[Any, int] = {}  # geometry id -> body index, filled as contacts name them
        plant.get_applied_spatial_force_input_port().FixValue(self.context, [])
        self._applied = False  # whether a non-zero wrench is fixed on the port
        # every second simulated, those of branches :meth:`restore` went back from included, s
        self.simulated_s = 0.0
        self.set_object_wrench(np.zeros(3), np.zeros(3))

    # --- the hand --------------------------------------------------------------------------
    def hand_q(self) -> np.ndarray:
        """The hand's joint values, planner order."""
        return np.asarray(self.plant.GetPositions(self.context))[self._index]

    def set_hand_q(self, q: np.ndarray) -> None:
        """Place the hand at ``q`` (at rest) and hold it there."""
        full = np.array(self.plant.GetPositions(self.context))
        full[self._index] = q
        self.plant.SetPositions(self.context, full)
        v = np.array(self.plant.GetVelocities(self.context))
        v[:] = 0.0
        self.plant.SetVelocities(self.context, v)
        self.command(q)

    def command(self, q: np.ndarray) -> None:
        """The PD controllers' target: joint values ``q`` (planner order), zero velocity."""
        target = np.concatenate([np.asarray(q, dtype=float), np.zeros(self._n)])
        self.plant.get_desired_state_input_port(self.model).FixValue(self.context, target)

    def command_moving(self, q: np.ndarray, v: np.ndarray) -> None:
        """The PD controllers' target: joint values ``q`` moving at ``v`` (planner order)."""
        target = np.concatenate([np.asarray(q, dtype=float), np.asarray(v, dtype=float)])
        self.plant.get_desired_state_input_port(self.model).FixValue(self.context, target)

    def advance_to(self, t: float) -> None:
        """Simulate up to time ``t``, s (in steps of at most ``rolling_update`` s, the rolling
        resistance's torque updated before each; added to :attr:`simulated_s`)."""
        step = self.settings.rolling_update
        start = self.root.get_time()
        while self.root.get_time() < t - 1e-12:
            self._apply_wrench()
            self.simulator.AdvanceTo(min(t, self.root.get_time() + step))
        self.simulated_s += max(0.0, self.root.get_time() - start)

    def save(self) -> Any:
        """A copy of the simulation's state (time, positions, velocities)."""
        return self.root.Clone()

    def restore(self, saved: Any) -> None:
        """Back to a state :meth:`save` made."""
        self.root.SetTimeStateAndParametersFrom(saved)
        self.simulator.Initialize()

    def body_pose(self, name: str) -> RigidTransform:
        """The pose of the hand's body ``name`` in the world."""
        return self.plant.EvalBodyPoseInWorld(self.context, self.plant.GetBodyByName(name, self.model))

    def advance(self, seconds: float) -> None:
        """Simulate ``seconds`` more."""
        self.advance_to(self.root.get_time() + seconds)

    def time(self) -> float:
        """Simulated time, s."""
        return float(self.root.get_time())

    # --- the object ----------------------------------------------------------------------------
    def object_pose(self) -> RigidTransform:
        """The object's pose in the world."""
        return self.plant.EvalBodyPoseInWorld(self.context, self.body)

    def set_object_wrench(self, force: np.ndarray, torque: np.ndarray) -> None:
        """An external force (N) at the object's centre and a torque (N·m), world frame (the
        rolling resistance's torque is added to it as the simulation runs)."""
        self._wrench = (np.asarray(force, dtype=float), np.asarray(torque, dtype=float))
        self._apply_wrench()

    def rolling_torque(self) -> np.ndarray:
        """The table's rolling resistance on the object (N·m, world): ``c N h`` (c: the
        coefficient, N: the table's normal force, h: the centre's height above the table)
        against the object's rolling about horizontal axes, viscous below 0.05 rad/s."""
        c = self.settings.rolling_resistance
        if c <= 0.0:
            return np.zeros(3)
        spin = np.array(self.plant.EvalBodySpatialVelocityInWorld(self.context, self.body).rotational())
        spin[2] = 0.0
        if float(np.linalg.norm(spin)) < STILL_SPIN:  # not rolling: no torque worth applying
            return np.zeros(3)
        normal = self.table_force()
        if normal <= 0.0:
            return np.zeros(3)
        height = max(0.0, float(self.object_pose().translation()[2]) - self.table_top)
        return -c * normal * height * spin / max(float(np.linalg.norm(spin)), 0.05)

    def table_force(self) -> float:
        """The table's normal force on the object (N)."""
        results = self.plant.get_contact_results_output_port().Eval(self.context)
        total = 0.0
        for i in range(results.num_hydroelastic_contacts()):
            info = results.hydroelastic_contact_info(i)
            surface = info.contact_surface()
            if self._table_geometry in (surface.id_M(), surface.id_N()):
                total += abs(float(info.F_Ac_W().translational()[2]))
        return total

    def _apply_wrench(self) -> None:
        from pydrake.multibody.math import SpatialForce
        from pydrake.multibody.plant import ExternallyAppliedSpatialForce

        force, torque = self._wrench
        torque = torque + self.rolling_torque()
        if not force.any() and not torque.any():  # nothing applied: fix the port only if it changes
            if not self._applied:
                return
            self.plant.get_applied_spatial_force_input_port().FixValue(self.context, [])
            self._applied = False
            return
        self._applied = True
        f = ExternallyAppliedSpatialForce()
        f.body_index = self.body.index()
        f.p_BoBq_B = vec((0.0, 0.0, 0.0))
        f.F_Bq_W = SpatialForce(vec(torque), vec(force))
        self.plant.get_applied_spatial_force_input_port().FixValue(self.context, [f])

    def object_contacts(self) -> list[tuple[int, np.ndarray, np.ndarray, float]]:
        """Every contact of the object: (other body index, point (m), unit normal out of the
        object, normal force (N)), from the plant's contact results (the hand's are point
        contacts; the table's a hydroelastic patch: its centroid, and its whole force)."""
        results = self.plant.get_contact_results_output_port().Eval(self.context)
        me = self.body.index()
        out = []
        for i in range(results.num_point_pair_contacts()):
            info = results.point_pair_contact_info(i)
            a, b = info.bodyA_index(), info.bodyB_index()
            if me not in (a, b):
                continue
            normal = np.asarray(info.point_pair().nhat_BA_W)  # from B into A
            force = np.asarray(info.contact_force())  # on B, world
            if b == me:  # normal out of the object (B) toward A
                other, n_out, f_on_obj = a, normal, force
            else:
                other, n_out, f_on_obj = b, -normal, -force
            pushing = float(max(0.0, -f_on_obj @ n_out))
            out.append((int(other), np.asarray(info.contact_point()), n_out, pushing))
        body_of = self._body_of_geometry
        for i in range(results.num_hydroelastic_contacts()):  # patches: the table's, soft fingertips'
            info = results.hydroelastic_contact_info(i)
            surface = info.contact_surface()
            a, b = body_of(surface.id_M()), body_of(surface.id_N())  # body A: geometry M's
            if me not in (a, b):
                continue
            f_on_obj = np.asarray(info.F_Ac_W().translational())
            other = b if a == me else a
            if a != me:
                f_on_obj = -f_on_obj
            if self._table_geometry in (surface.id_M(), surface.id_N()):  # the table's: normal −z
                out.append((other, np.asarray(surface.centroid()), DOWN, float(max(0.0, f_on_obj[2]))))
                continue
            # the patch's area-weighted normal (Drake's face normals point out of N into M)
            faces = range(surface.num_faces())
            mean = sum((surface.area(f) * np.asarray(surface.face_normal(f)) for f in faces), np.zeros(3))
            norm = float(np.linalg.norm(mean))
            n_out = (mean if a != me else -mean) / norm if norm > 0.0 else np.array([0.0, 0.0, -1.0])
            pushing = float(max(0.0, -f_on_obj @ n_out))
            out.append((other, np.asarray(surface.centroid()), n_out, pushing))
        return out

    def _body_of_geometry(self, geometry: Any) -> int:
        """The index of the body a geometry belongs to."""
        body = self._bodies.get(geometry)
        if body is None:
            body = int(self.plant.GetBodyFromFrameId(self._inspector.GetFrameId(geometry)).index())
            self._bodies[geometry] = body
        return body

    def tip_force(self, finger_body: Any) -> tuple[np.ndarray, np.ndarray, float] | None:
        """The contact of a fingertip body with the object: (point, normal, force) or None."""
        best = None
        for other, point, normal, force in self.object_contacts():
            if other == int(finger_body.index()) and (best is None or force > best[2]):
                best = (point, normal, force)
        return best
