"""Other hands for the planner: the Allegro right hand of example-robot-data on a 6-DoF wrist.

The grasp planner (``eos_svc.agents``) expects what hand3x3 offers: six 1-DoF wrist joints
(x, y, z prismatic, then roll, pitch, yaw) in front of a palm frame whose x axis is the
approach direction and whose z axis the closing direction (the other fingers above, the
opposing finger below), and fingers that close by adding the same angle to each of their
listed joints. The Allegro URDF has no wrist, so :func:`allegro_hand` builds a composite URDF
at run time from the installed file (never a hard-coded path): the six wrist joints, a
``palm`` link (the planner's palm frame) and a fixed ``allegro_mount`` joint to the Allegro's
``palm_link``.

Mounting (see ``docs/planner.md``, "Other hands"): the Allegro's palm faces the approach
direction: its palm normal (``palm_link`` +x) is the palm frame's +x, its fingers point up
(``palm_link`` +z = palm +z), the thumb sits below them. Curling, the fingertips come
forward and down in front of the palm; the opposed thumb comes up and back toward them:
the fingertips oppose the thumb along z, about 9 cm in front of the palm. The mount lowers
the Allegro so that the palm frame's x axis (the planner's hand axis) runs between them.

Pre-shape (:class:`PreShapedHandModel`): the joints that are not a finger's flexion joints
hold a fixed value in the hand's neutral configuration — the thumb rotated into opposition
(``joint_12.0``) and twisted toward the middle finger (``joint_13.0``), the index and ring
fingers abducted toward the middle finger (``joint_0.0``, ``joint_8.0``) so their tips close
on a small object too. Each finger's listed joints are its flexion joints (index, middle,
ring: the three joints after the abduction joint; thumb: its two distal joints).
"""

from __future__ import annotations

import functools
import importlib.metadata
import os
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from .hand import FingerDescription, HandDescription, HandModel, UrdfLoadError
from .urdf_loading import capture_stderr

__all__ = [
    "ALLEGRO_MOUNT_XYZ",
    "ALLEGRO_PRESHAPE",
    "PreShapedHandModel",
    "allegro_description",
    "allegro_hand",
    "allegro_urdf_path",
    "composite_urdf",
    "example_robot_data_share",
    "load_composite_hand",
]

#: the Allegro URDF inside example-robot-data's share directory
_ALLEGRO_RELATIVE = "example-robot-data/robots/allegro_hand_description/urdf/allegro_right_hand.urdf"

#: where the Allegro's ``palm_link`` sits in the planner's palm frame (m): lowered so that
#: the palm frame's x axis runs between the closing fingertips and the thumb
ALLEGRO_MOUNT_XYZ: tuple[float, float, float] = (0.0, 0.0, -0.02)

#: fixed values of the joints that are not flexion joints, in the hand's neutral (rad)
ALLEGRO_PRESHAPE: Mapping[str, float] = {
    "joint_0.0": -0.35,  # index abducted toward the middle finger
    "joint_4.0": 0.0,
    "joint_8.0": 0.35,  # ring abducted toward the middle finger
    "joint_12.0": 1.396,  # thumb rotated into opposition (its upper limit)
    "joint_13.0": 0.45,  # thumb twisted toward the middle finger
}

#: the six wrist joints: name, type, axis, lower, upper, effort, velocity (as hand3x3)
_WRIST = (
    ("wrist_x", "prismatic", "1 0 0", -0.5, 0.5, 50.0, 0.5),
    ("wrist_y", "prismatic", "0 1 0", -0.5, 0.5, 50.0, 0.5),
    ("wrist_z", "prismatic", "0 0 1", -0.5, 0.5, 50.0, 0.5),
    ("wrist_roll", "revolute", "1 0 0", -np.pi, np.pi, 5.0, 2.0),
    ("wrist_pitch", "revolute", "0 1 0", -np.pi / 2, np.pi / 2, 5.0, 2.0),
    ("wrist_yaw", "revolute", "0 0 1", -np.pi / 2, np.pi / 2, 5.0, 2.0),
)
WRIST_JOINTS: tuple[str, ...] = tuple(w[0] for w in _WRIST)


def example_robot_data_share() -> Path:
    """``.../share`` of the installed example-robot-data distribution (found from its files).

    Raises:
        UrdfLoadError: example-robot-data is not installed or has no Allegro URDF.
    """
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError as exc:
        raise UrdfLoadError("example-robot-data", "the distribution is not installed") from exc
    for f in dist.files or []:
        if str(f).replace("\\", "/").endswith(_ALLEGRO_RELATIVE):
            urdf = Path(str(dist.locate_file(f))).resolve()
            return urdf.parents[len(Path(_ALLEGRO_RELATIVE).parts) - 1]
    raise UrdfLoadError("example-robot-data", f"no {_ALLEGRO_RELATIVE} in the distribution")


def allegro_urdf_path() -> Path:
    """The installed Allegro right-hand URDF."""
    return example_robot_data_share() / _ALLEGRO_RELATIVE


def allegro_description(tip_radius: float = 0.012) -> HandDescription:
    """The composite Allegro hand: four fingers listed by their flexion joints, sphere tips
    (r = 12 mm, the URDF's), the thumb opposing, the six wrist joints, palm frame ``palm``."""
    fingers = []
    for name, first, flexion in (("index", 0, 3), ("middle", 4, 3), ("ring", 8, 3), ("thumb", 12, 2)):
        last = first + 3
        fingers.append(
            FingerDescription(
                name=name,
                joints=tuple(f"joint_{k}.0" for k in range(last - flexion + 1, last + 1)),
                tip_frame=f"link_{last}.0_tip",
                tip_radius=tip_radius,
                tip_geometry=f"link_{last}.0_tip_0",
            )
        )
    return HandDescription(
        fingers=tuple(fingers),
        wrist_joints=WRIST_JOINTS,
        opposing_finger="thumb",
        palm_frame="palm",
    )


def _fmt(v: float) -> str:
    return f"{v:.9g}"


def _inertial(link: ET.Element, mass: float = 0.01) -> None:
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", xyz="0 0 0", rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=_fmt(mass))
    ET.SubElement(inertial, "inertia", ixx="1e-06", ixy="0", ixz="0", iyy="1e-06", iyz="0", izz="1e-06")


def composite_urdf(
    urdf_path: str | os.PathLike[str],
    root_link: str,
    mount_xyz: Sequence[float] = (0.0, 0.0, 0.0),
    mount_rpy: Sequence[float] = (0.0, 0.0, 0.0),
) -> str:
    """URDF text of a fixed-base hand put on the six wrist joints of hand3x3.

    ``world → wrist_x → … → wrist_yaw → palm`` (the planner's palm frame), then a fixed joint
    ``<robot>_mount`` from ``palm`` to the hand's ``root_link`` at ``mount_xyz``/``mount_rpy``.

    Raises:
        UrdfLoadError: the file cannot be parsed or has no link ``root_link``.
    """
    try:
        root = ET.parse(str(urdf_path)).getroot()
    except (OSError, ET.ParseError) as exc:
        raise UrdfLoadError("urdf_path", f"cannot read {urdf_path}: {exc}") from exc
    if not any(link.get("name") == root_link for link in root.iter("link")):
        raise UrdfLoadError("urdf_path", f"{urdf_path} has no link {root_link!r}")
    added: list[ET.Element] = [ET.Element("link", name="world")]
    parent = "world"
    for k, (name, kind, axis, lo, hi, effort, velocity) in enumerate(_WRIST):
        child = "palm" if k == len(_WRIST) - 1 else f"{name}_link"
        link = ET.Element("link", name=child)
        _inertial(link)
        joint = ET.Element("joint", name=name, type=kind)
        ET.SubElement(joint, "parent", link=parent)
        ET.SubElement(joint, "child", link=child)
        ET.SubElement(joint, "origin", xyz="0 0 0", rpy="0 0 0")
        ET.SubElement(joint, "axis", xyz=axis)
        ET.SubElement(
            joint, "limit", lower=_fmt(lo), upper=_fmt(hi), effort=_fmt(effort), velocity=_fmt(velocity)
        )
        added += [link, joint]
        parent = child
    mount = ET.Element("joint", name=f"{root.get('name', 'hand')}_mount", type="fixed")
    ET.SubElement(mount, "parent", link="palm")
    ET.SubElement(mount, "child", link=root_link)
    ET.SubElement(
        mount,
        "origin",
        xyz=" ".join(_fmt(v) for v in mount_xyz),
        rpy=" ".join(_fmt(v) for v in mount_rpy),
    )
    added.append(mount)
    for k, element in enumerate(added):
        root.insert(k, element)
    return ET.tostring(root, encoding="unicode")


class PreShapedHandModel(HandModel):
    """A :class:`HandModel` whose neutral configuration holds a fixed pre-shape.

    Joints named in ``preshape`` take that value in :meth:`neutral` (every other joint its
    Pinocchio neutral, 0 for a revolute or prismatic joint). The planner never moves a joint
    that is neither a wrist joint nor listed in a finger, so the pre-shape holds all along.
    """

    def __init__(
        self,
        model: pin.Model,
        collision_model: pin.GeometryModel,
        description: HandDescription,
        preshape: Mapping[str, float],
        urdf_path: Path | None = None,
        load_warnings: str = "",
    ) -> None:
        q = np.array(pin.neutral(model), dtype=float)
        for name, value in preshape.items():
            if not model.existJointName(name):
                raise UrdfLoadError("preshape", f"joint {name!r} is not in the model")
            joint = model.joints[model.getJointId(name)]
            lo, hi = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
            if not lo - 1e-12 <= value <= hi + 1e-12:
                raise UrdfLoadError("preshape", f"{name} = {value} is outside [{lo}, {hi}]")
            q[joint.idx_q] = value
        self._neutral = q  # before HandModel.__init__: it computes the hand height at neutral()
        self.preshape: dict[str, float] = dict(preshape)
        super().__init__(model, collision_model, description, urdf_path, load_warnings)

    def neutral(self) -> np.ndarray:
        """The pre-shaped neutral configuration (a copy): wrist at 0, fingers straight."""
        return self._neutral.copy()


def load_composite_hand(
    urdf_path: str | os.PathLike[str],
    root_link: str,
    description: HandDescription,
    package_dirs: Sequence[str | os.PathLike[str]] = (),
    mount_xyz: Sequence[float] = (0.0, 0.0, 0.0),
    mount_rpy: Sequence[float] = (0.0, 0.0, 0.0),
    preshape: Mapping[str, float] | None = None,
) -> PreShapedHandModel:
    """Load a fixed-base hand URDF on the six wrist joints (see :func:`composite_urdf`).

    Raises:
        UrdfLoadError: the URDF cannot be read or loaded, or the pre-shape names an unknown
            joint or a value outside its limits.
        HandDescriptionError / UnknownNameError: the description does not match the model.
    """
    text = composite_urdf(urdf_path, root_link, mount_xyz, mount_rpy)
    dirs = [str(Path(p)) for p in package_dirs]
    # buildGeomFromUrdf reads a file: write the composite next to nothing else, then remove it
    fd, tmp = tempfile.mkstemp(suffix=".urdf", prefix="eos_composite_")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        with capture_stderr() as err:
            model = pin.buildModelFromXML(text)
            gmodel = pin.buildGeomFromUrdf(model, tmp, pin.COLLISION, package_dirs=dirs)
    except Exception as exc:  # Pinocchio raises ValueError/RuntimeError with a parser message
        raise UrdfLoadError(
            "urdf_path", f"Pinocchio cannot load the composite of {urdf_path}: {exc}"
        ) from exc
    finally:
        os.unlink(tmp)
    for g in gmodel.geometryObjects:
        if not isinstance(g.geometry, coal.CollisionGeometry):  # pragma: no cover - defensive
            raise UrdfLoadError("collision", f"geometry {g.name!r} did not load")
    return PreShapedHandModel(
        model,
        gmodel,
        description,
        preshape or {},
        urdf_path=Path(urdf_path),
        load_warnings=err.getvalue().strip(),
    )


@functools.lru_cache(maxsize=1)
def allegro_hand() -> PreShapedHandModel:
    """The Allegro right hand of example-robot-data on a 6-DoF wrist, pre-shaped (cached).

    22 joints: the six wrist joints, then the Allegro's sixteen (Pinocchio's order: index,
    thumb, middle, ring). Fingers ``index``, ``middle``, ``ring`` (upper) and ``thumb``
    (opposing), fingertip spheres r = 12 mm. See the module docstring for the mounting.
    """
    share = example_robot_data_share()
    return load_composite_hand(
        share / _ALLEGRO_RELATIVE,
        "palm_link",
        allegro_description(),
        package_dirs=[share],
        mount_xyz=ALLEGRO_MOUNT_XYZ,
        preshape=ALLEGRO_PRESHAPE,
    )
