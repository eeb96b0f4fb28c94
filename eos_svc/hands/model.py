"""A hand built from a description: the :class:`~eos_svc.kinematics.HandModel` the planner uses,
plus what the description says beyond kinematics (pre-shape, world parameters, Drake settings)
and the URDF text it was loaded from (the Drake validation parses the same text)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from eos_svc.kinematics import HandDescription, HandModel
from eos_svc.kinematics.errors import HandDescriptionError

from .spec import HandSpec

__all__ = ["DescribedHand"]


class DescribedHand(HandModel):
    """A :class:`HandModel` made from a :class:`~eos_svc.hands.spec.HandSpec`.

    Its neutral configuration holds the description's pre-shape (given in the URDF's
    convention): joints that are neither wrist nor finger joints keep that value all along (the
    planner never moves them); a finger joint starts there (a gripper that starts open). Every finger joint
    closes toward +q (joints whose closing direction is −1 were reversed in the URDF text).

    Attributes:
        spec: the description.
        urdf_text: the URDF the model was loaded from (composite when the description adds a
            wrist, tips, collision primitives or reverses joints).
        package_dirs: where ``package://`` URIs of the text resolve.
        world_overrides: the description's ``[world]`` parameters.
        drake: the description's ``[drake]`` settings (kp, kd, squeeze).
        preshape: pre-shape joint values as the description gives them (URDF convention; rad or m).
    """

    def __init__(
        self,
        model: pin.Model,
        collision_model: pin.GeometryModel,
        description: HandDescription,
        spec: HandSpec,
        urdf_text: str,
        package_dirs: list[Path],
        urdf_path: Path | None = None,
        load_warnings: str = "",
    ) -> None:
        q = np.array(pin.neutral(model), dtype=float)
        reversed_joints = {j for f in spec.fingers for j, c in zip(f.joints, f.closing, strict=True) if c < 0}
        for name, urdf_value in spec.preshape.items():
            where = f"preshape.{name}"
            if not model.existJointName(name):
                raise HandDescriptionError(where, f"joint {name!r} is not in the URDF")
            if name in description.wrist_joints:
                raise HandDescriptionError(where, "a wrist joint cannot be pre-shaped")
            value = -urdf_value if name in reversed_joints else urdf_value
            joint = model.joints[model.getJointId(name)]
            if joint.nq != 1:
                raise HandDescriptionError(where, f"joint {name!r} is not a 1-DoF joint")
            lo, hi = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
            if not lo - 1e-12 <= value <= hi + 1e-12:
                raise HandDescriptionError(where, f"{value} is outside the joint's limits [{lo}, {hi}]")
            q[joint.idx_q] = value
        self._neutral = q  # before HandModel.__init__: it computes the hand height at neutral()
        self.spec = spec
        self.urdf_text = urdf_text
        self.package_dirs = list(package_dirs)
        self.world_overrides: Mapping[str, Any] = dict(spec.world)
        self.drake: Mapping[str, float] = dict(spec.drake)
        self.preshape: dict[str, float] = dict(spec.preshape)
        super().__init__(model, collision_model, description, urdf_path, load_warnings)

    @property
    def name(self) -> str:
        """The description's name (``hand3x3``, ``allegro``, ``trifinger`` …)."""
        return self.spec.name

    def neutral(self) -> np.ndarray:
        """The pre-shaped neutral configuration (a copy): wrist at 0, fingers at 0 (or their
        lower limit's side, as Pinocchio's neutral), pre-shaped joints at their values."""
        return self._neutral.copy()

    def __repr__(self) -> str:
        fingers = self.finger_names
        return f"DescribedHand({self.name!r}, nq={self.nq}, fingers={fingers}, h={self.hand_height:.4f} m)"
