"""From a description to a hand: compose the URDF, load it with Pinocchio (model and coal
collision geometry), match the description against it."""

from __future__ import annotations

import os
import tempfile

import pinocchio as pin

from eos_svc.kinematics import FingerDescription, HandDescription
from eos_svc.kinematics.errors import HandDescriptionError, KinematicsError
from eos_svc.kinematics.urdf_loading import capture_stderr

from .composite import ComposedUrdf, added_tip_link, compose_urdf
from .model import DescribedHand
from .spec import HandSpec

__all__ = ["build_hand", "hand_description"]


def hand_description(spec: HandSpec) -> HandDescription:
    """The planner's :class:`HandDescription` of ``spec`` (added tips named by
    :func:`~eos_svc.hands.composite.added_tip_link`)."""
    fingers = []
    for i, f in enumerate(spec.fingers):
        frame: str = added_tip_link(f.name) if f.tip.link is not None else str(f.tip.frame)
        geometry = f"{frame}_0" if f.tip.link is not None else f.tip.geometry
        try:
            fingers.append(FingerDescription(f.name, f.joints, frame, f.tip.radius, geometry))
        except HandDescriptionError as exc:
            raise HandDescriptionError(f"fingers[{i}]", exc.reason) from None
    return HandDescription(
        fingers=tuple(fingers),
        wrist_joints=spec.wrist.joints,
        opposing_finger=spec.opposing_finger,
        palm_frame=spec.wrist.palm_frame,
    )


def _load(composed: ComposedUrdf) -> tuple[pin.Model, pin.GeometryModel, str]:
    dirs = [str(p) for p in composed.package_dirs]
    if composed.unchanged:  # the file itself, as kinematics.load_hand loads it
        with capture_stderr() as err:
            model = pin.buildModelFromUrdf(str(composed.path))
            gmodel = pin.buildGeomFromUrdf(model, str(composed.path), pin.COLLISION, package_dirs=dirs)
        return model, gmodel, err.getvalue().strip()
    fd, tmp = tempfile.mkstemp(suffix=".urdf", prefix="eos_hand_")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(composed.text)
        with capture_stderr() as err:
            model = pin.buildModelFromXML(composed.text)
            gmodel = pin.buildGeomFromUrdf(model, tmp, pin.COLLISION, package_dirs=dirs)
    finally:
        os.unlink(tmp)
    return model, gmodel, err.getvalue().strip()


def build_hand(spec: HandSpec) -> DescribedHand:
    """The hand ``spec`` describes.

    Raises:
        HandDescriptionError: naming the key that does not match the URDF (a missing joint,
            link or frame, a tip radius that is not the URDF sphere's, a joint without limits).
        UrdfLoadError: the URDF cannot be found or Pinocchio cannot load it.
    """
    composed = compose_urdf(spec)
    try:
        model, gmodel, warnings = _load(composed)
    except KinematicsError:
        raise
    except Exception as exc:  # Pinocchio raises ValueError/RuntimeError with a parser message
        raise HandDescriptionError("urdf", f"Pinocchio cannot load {composed.path}: {exc}") from exc
    description = hand_description(spec)
    try:
        return DescribedHand(
            model,
            gmodel,
            description,
            spec,
            composed.text,
            composed.package_dirs,
            urdf_path=composed.path,
            load_warnings=warnings,
        )
    except HandDescriptionError as exc:
        raise HandDescriptionError(_spec_key(spec, exc.field), exc.reason) from None


def _spec_key(spec: HandSpec, field: str) -> str:
    """The description key of a :class:`HandModel` field (``finger2.tip_frame`` → ``fingers[1].tip``)."""
    head, _, rest = field.partition(".")
    for i, f in enumerate(spec.fingers):
        if head == f.name:
            return f"fingers[{i}]." + {
                "tip_frame": "tip",
                "tip_geometry": "tip.geometry",
                "tip_radius": "tip.radius",
            }.get(rest, rest)
    if head == "wrist" or field == "wrist_joints":
        return "wrist.joints"
    if field == "palm_frame":
        return "wrist.palm_frame"
    return field
