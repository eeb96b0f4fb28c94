"""The URDF a description makes: its parts on the palm, on a floating wrist when it asks for one.

What the builder changes, always in a copy of the text (the installed files are never touched):

- a floating wrist: ``world → wrist_x → … → wrist_yaw → palm`` (six 1-DoF joints), then each
  part's root link fixed to ``palm`` at its ``xyz``/``rpy`` (joint ``<robot>_mount``);
- each part's link, joint and material names get its ``prefix`` (three finger_edu fingers are
  one TriFinger hand);
- a finger joint whose closing direction is −1 has its axis reversed and its limits mirrored,
  so that every finger joint closes toward +q (the planner's convention: a finger closes by
  adding the same increment to each of its joints); its coordinate is the URDF's negated;
- a part's links and joints outside its ``root_link``'s subtree are dropped (a hand taken off
  the arm it is shipped with);
- ``<mimic>`` and ``<transmission>`` elements are dropped (each finger is its own agent);
- limits named in ``[limits]`` (lower, upper, effort, velocity) replace the URDF's, before
  any reversal (they are in the URDF's convention);
- ``[collision]``: the collision elements of the ``replace`` links are removed, the ``add``
  primitives attached;
- an added fingertip (``tip.link``) becomes a link ``<finger>_tip_sphere`` fixed to that link
  at ``tip.xyz``, with one collision sphere of ``tip.radius``.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

from eos_svc.kinematics.errors import HandDescriptionError

from .sources import resolve_urdf
from .spec import HandSpec, PartSpec

__all__ = ["ComposedUrdf", "added_tip_link", "compose_urdf"]


class ComposedUrdf:
    """A description's URDF text, the package directories its meshes need, and whether it is
    the part's file unchanged (then loaded from ``path`` directly)."""

    def __init__(self, text: str, package_dirs: list[Path], path: Path, unchanged: bool) -> None:
        self.text = text
        self.package_dirs = package_dirs
        self.path = path
        self.unchanged = unchanged


def added_tip_link(finger: str) -> str:
    """The link (and Pinocchio frame) the builder adds for an added fingertip sphere."""
    return f"{finger}_tip_sphere"


def _fmt(v: float) -> str:
    return f"{v:.9g}"


def _inertial(link: ET.Element, mass: float = 0.01) -> None:
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", xyz="0 0 0", rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=_fmt(mass))
    ET.SubElement(inertial, "inertia", ixx="1e-06", ixy="0", ixz="0", iyy="1e-06", iyz="0", izz="1e-06")


def _key(where: str, name: str) -> str:
    """The description key ``name`` of a part (``parts[1].root_link``, or ``root_link`` for a
    one-URDF hand)."""
    return f"{where}.{name}" if where else name


def _read(part: PartSpec, where: str) -> tuple[ET.Element, Path, list[Path]]:
    path, dirs = resolve_urdf(part.urdf, _key(where, "urdf"))
    try:
        root = ET.parse(str(path)).getroot()
    except (OSError, ET.ParseError) as exc:
        raise HandDescriptionError(_key(where, "urdf"), f"cannot read {path}: {exc}") from exc
    return root, path, dirs


def _subtree(root: ET.Element, root_link: str) -> None:
    """Keep only ``root_link`` and what hangs from it (a hand taken off its arm)."""
    children: dict[str, list[str]] = {}
    for joint in root.iter("joint"):
        parent, child = joint.find("parent"), joint.find("child")
        if parent is not None and child is not None:
            children.setdefault(parent.get("link", ""), []).append(child.get("link", ""))
    keep, todo = set(), [root_link]
    while todo:
        link = todo.pop()
        keep.add(link)
        todo.extend(children.get(link, []))
    for element in list(root):
        if element.tag == "link" and element.get("name") not in keep:
            root.remove(element)
        elif element.tag == "joint":
            child = element.find("child")
            if child is None or child.get("link") not in keep or element.get("type") == "floating":
                root.remove(element)
            else:
                parent = element.find("parent")
                if parent is None or parent.get("link") not in keep:
                    root.remove(element)


def _prefixed(root: ET.Element, prefix: str) -> None:
    """Prefix every link, joint and material name of a part (and the references to them)."""
    if not prefix:
        return
    for link in root.iter("link"):
        link.set("name", prefix + link.get("name", ""))
    for joint in root.iter("joint"):
        joint.set("name", prefix + joint.get("name", ""))
        for tag in ("parent", "child"):
            ref = joint.find(tag)
            if ref is not None:
                ref.set("link", prefix + ref.get("link", ""))
    for material in root.iter("material"):
        if material.get("name"):
            material.set("name", prefix + material.get("name", ""))


def _wrist_elements(spec: HandSpec) -> list[ET.Element]:
    added: list[ET.Element] = [ET.Element("link", name="world")]
    parent = "world"
    axes = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1", "roll": "1 0 0", "pitch": "0 1 0", "yaw": "0 0 1"}
    names = list(spec.wrist.limits)
    for k, axis in enumerate(names):
        lo, hi, effort, velocity = spec.wrist.limits[axis]
        name = f"wrist_{axis}"
        child = "palm" if k == len(names) - 1 else f"{name}_link"
        link = ET.Element("link", name=child)
        _inertial(link)
        kind = "prismatic" if axis in ("x", "y", "z") else "revolute"
        joint = ET.Element("joint", name=name, type=kind)
        ET.SubElement(joint, "parent", link=parent)
        ET.SubElement(joint, "child", link=child)
        ET.SubElement(joint, "origin", xyz="0 0 0", rpy="0 0 0")
        ET.SubElement(joint, "axis", xyz=axes[axis])
        ET.SubElement(
            joint, "limit", lower=_fmt(lo), upper=_fmt(hi), effort=_fmt(effort), velocity=_fmt(velocity)
        )
        added += [link, joint]
        parent = child
    return added


def _mount(part: PartSpec, root: ET.Element, where: str) -> ET.Element:
    root_link = part.prefix + part.root_link
    if not any(link.get("name") == root_link for link in root.iter("link")):
        raise HandDescriptionError(_key(where, "root_link"), f"the URDF has no link {part.root_link!r}")
    mount = ET.Element("joint", name=f"{part.prefix}{root.get('name', 'hand')}_mount", type="fixed")
    ET.SubElement(mount, "parent", link="palm")
    ET.SubElement(mount, "child", link=root_link)
    ET.SubElement(mount, "origin", xyz=" ".join(map(_fmt, part.xyz)), rpy=" ".join(map(_fmt, part.rpy)))
    return mount


def _flip(joint: ET.Element, where: str) -> None:
    """Reverse a joint's axis and mirror its limits: its coordinate becomes the negated one."""
    axis = joint.find("axis")
    xyz = [float(v) for v in (axis.get("xyz", "1 0 0") if axis is not None else "1 0 0").split()]
    if axis is None:
        axis = ET.SubElement(joint, "axis")
    axis.set("xyz", " ".join(_fmt(-v) if v else "0" for v in xyz))
    limit = joint.find("limit")
    if limit is None or "lower" not in limit.attrib or "upper" not in limit.attrib:
        raise HandDescriptionError(where, f"joint {joint.get('name')!r} has no lower/upper limit to mirror")
    lo, hi = float(limit.get("lower", "0")), float(limit.get("upper", "0"))
    limit.set("lower", _fmt(-hi))
    limit.set("upper", _fmt(-lo))


def _primitive(collision: ET.Element, shape: str, size: dict[str, Any]) -> None:
    geometry = ET.SubElement(collision, "geometry")
    if shape == "sphere":
        ET.SubElement(geometry, "sphere", radius=_fmt(size["radius"]))
    elif shape == "box":
        ET.SubElement(geometry, "box", size=" ".join(map(_fmt, size["size"])))
    else:
        ET.SubElement(geometry, "cylinder", radius=_fmt(size["radius"]), length=_fmt(size["length"]))


def _needs_rewrite(spec: HandSpec) -> bool:
    return bool(
        spec.wrist.floating
        or any(c == -1 for f in spec.fingers for c in f.closing)
        or any(f.tip.link for f in spec.fingers)
        or spec.limits
        or spec.collision_replace
        or spec.collision_add
    )


def compose_urdf(spec: HandSpec) -> ComposedUrdf:
    """The URDF text of ``spec`` (see the module docstring).

    Raises:
        HandDescriptionError: naming the key whose file, link or joint is missing.
    """
    wheres = [part.where for part in spec.parts]
    first_root, first_path, dirs = _read(spec.parts[0], wheres[0])
    if not _needs_rewrite(spec):
        return ComposedUrdf(ET.tostring(first_root, encoding="unicode"), dirs, first_path, unchanged=True)
    robot = first_root
    if spec.wrist.floating:
        robot = ET.Element(
            "robot", name=first_root.get("name", spec.name) if len(spec.parts) == 1 else spec.name
        )
        body: list[ET.Element] = _wrist_elements(spec)
        materials: dict[str, ET.Element] = {}
        for i, part in enumerate(spec.parts):
            root, _path, part_dirs = (first_root, first_path, []) if i == 0 else _read(part, wheres[i])
            dirs += [d for d in part_dirs if d not in dirs]
            _prefixed(root, part.prefix)
            body.append(_mount(part, root, wheres[i]))
            _subtree(root, part.prefix + part.root_link)
            for element in list(root):
                if element.tag == "material":
                    materials.setdefault(element.get("name", ""), element)
                else:
                    body.append(element)
        for element in [*materials.values(), *body]:
            robot.append(element)
    _edit(robot, spec)
    return ComposedUrdf(ET.tostring(robot, encoding="unicode"), dirs, first_path, unchanged=False)


def _edit(robot: ET.Element, spec: HandSpec) -> None:
    """Closing flips, limits, mimic/transmission removal, collision edits, added tips."""
    joints = {j.get("name"): j for j in robot.iter("joint")}
    links = {link.get("name"): link for link in robot.iter("link")}
    for element in list(robot):
        if element.tag == "transmission":
            robot.remove(element)
    for joint in joints.values():
        for mimic in joint.findall("mimic"):
            joint.remove(mimic)
    for name, values in spec.limits.items():
        if name not in joints:
            raise HandDescriptionError(f"limits.{name}", f"joint {name!r} is not in the URDF")
        limit = joints[name].find("limit")
        if limit is None:
            limit = ET.SubElement(joints[name], "limit")
        for key, value in values.items():
            limit.set(key, _fmt(value))
    for i, finger in enumerate(spec.fingers):
        for k, (name, closing) in enumerate(zip(finger.joints, finger.closing, strict=True)):
            if name not in joints:
                raise HandDescriptionError(f"fingers[{i}].joints[{k}]", f"joint {name!r} is not in the URDF")
            if closing == -1:
                _flip(joints[name], f"fingers[{i}].closing[{k}]")
    for k, name in enumerate(spec.collision_replace):
        if name not in links:
            raise HandDescriptionError(f"collision.replace[{k}]", f"link {name!r} is not in the URDF")
        for collision in links[name].findall("collision"):
            links[name].remove(collision)
    for k, add in enumerate(spec.collision_add):
        if add.link not in links:
            raise HandDescriptionError(f"collision.add[{k}].link", f"link {add.link!r} is not in the URDF")
        collision = ET.SubElement(links[add.link], "collision")
        ET.SubElement(collision, "origin", xyz=" ".join(map(_fmt, add.xyz)), rpy=" ".join(map(_fmt, add.rpy)))
        _primitive(collision, add.shape, add.size)
    for i, finger in enumerate(spec.fingers):
        tip = finger.tip
        if tip.link is None:
            continue
        if tip.link not in links:
            raise HandDescriptionError(f"fingers[{i}].tip.link", f"link {tip.link!r} is not in the URDF")
        name = added_tip_link(finger.name)
        if name in links:
            raise HandDescriptionError(f"fingers[{i}].tip.link", f"the URDF already has a link {name!r}")
        link = ET.SubElement(robot, "link", name=name)
        _inertial(link, mass=0.001)
        collision = ET.SubElement(link, "collision")
        ET.SubElement(collision, "origin", xyz="0 0 0", rpy="0 0 0")
        _primitive(collision, "sphere", {"radius": tip.radius})
        joint = ET.SubElement(robot, "joint", name=f"{name}_joint", type="fixed")
        ET.SubElement(joint, "parent", link=tip.link)
        ET.SubElement(joint, "child", link=name)
        ET.SubElement(joint, "origin", xyz=" ".join(map(_fmt, tip.xyz)), rpy="0 0 0")
