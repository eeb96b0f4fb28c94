"""The hand as Drake reads it: the URDF the planner's model was loaded from, as a file.

A :class:`~eos_svc.hands.DescribedHand` carries the URDF text its description makes (a
composite when it adds a wrist, tips, primitives or reverses joints); Drake's parser reads
files, so the text is written to a temporary file for the validation's lifetime, without its
``<visual>`` elements (the simulation draws nothing, and Drake need not load visual meshes)
and without joint ``friction`` (which Drake's plant does not model; it would warn).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path

from eos_svc.errors import ValidationError
from eos_svc.kinematics import HandModel

__all__ = ["drake_urdf", "model_joint_names"]


def model_joint_names(hand: HandModel) -> list[str]:
    """The hand's joints in the order of its configuration ``q`` (each 1-DoF)."""
    model = hand.model
    names = []
    for joint_id in range(1, model.njoints):
        if model.joints[joint_id].nq != 1:
            raise ValidationError("hand", f"joint {model.names[joint_id]!r} is not a 1-DoF joint")
        names.append(str(model.names[joint_id]))
    return names


@contextlib.contextmanager
def drake_urdf(hand: HandModel) -> Iterator[tuple[Path, list[Path]]]:
    """A URDF file of ``hand`` for Drake and the package directories it needs (removed after)."""
    text = getattr(hand, "urdf_text", None)
    dirs = [Path(p) for p in getattr(hand, "package_dirs", [])]
    if text is None:
        if hand.urdf_path is None:
            raise ValidationError("hand", "the hand model has no URDF to give Drake")
        text = Path(hand.urdf_path).read_text(encoding="utf-8")
    root = ET.fromstring(text)
    for link in root.iter("link"):
        for visual in link.findall("visual"):
            link.remove(visual)
    for dynamics in root.iter("dynamics"):  # Drake has no joint friction (it would warn)
        dynamics.attrib.pop("friction", None)
    fd, tmp = tempfile.mkstemp(suffix=".urdf", prefix="eos_drake_")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(ET.tostring(root, encoding="unicode"))
        yield Path(tmp), dirs
    finally:
        os.unlink(tmp)
