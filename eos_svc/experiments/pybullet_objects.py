"""Test objects nobody here wrote: the meshes of the ``pybullet`` package's data (zlib licence).

``pip install eos_svc[objects]`` installs ``pybullet``, whose ``pybullet_data`` holds 1,000
procedurally generated random objects (``random_urdfs/NNN/NNN.obj``) and a few household
ones: a mug (``objects/mug.obj``), a duck (``duck_vhacd.obj``) and a teddy bear
(``teddy2_VHACD_CHs.obj``). They are read from the installed package, never copied here.

Each object becomes a mesh request (``{"shape": "mesh", "file", "scale", "position", "rpy"}``)
resting on a table:

- **size**: scaled so its thinnest principal extent is a width the hand can span, drawn per
  object id in [:data:`THIN_MIN`, :data:`THIN_MAX`] m — and no larger than keeps its longest
  extent within :data:`LONGEST_MAX` m; an object too elongated for both is left out
  (:func:`random_object` returns None);
- **pose**: its principal axes of inertia turned to the world's: the thinnest across the
  hand's approach (y), the longest along it (x), the middle one upright (z) — a grasp across
  the thinnest width from above or the side;
- **place**: its centre of mass over :data:`PLACE` (x, y), its lowest point on the table at
  :data:`TABLE_HEIGHT`.
"""

from pathlib import Path
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from eos_svc.errors import ValidationError
from eos_svc.objects import Mesh
from eos_svc.schema.request import ObjectSpec, Table

#: the thinnest extent's range (m): what the hand can span across a grip
THIN_MIN, THIN_MAX = 0.04, 0.10
#: the longest extent allowed (m)
LONGEST_MAX = 0.16
#: the table's height (world z, m) and where the object's centre of mass stands over it (x, y, m)
TABLE_HEIGHT = -0.05
PLACE = (0.21, 0.02)
#: the household objects: name → file in pybullet_data
NAMED = {"mug": "objects/mug.obj", "duck": "duck_vhacd.obj", "teddy": "teddy2_VHACD_CHs.obj"}
#: how many random objects pybullet_data has
RANDOM_COUNT = 1000


class WorldObject(NamedTuple):
    """A test object resting on the table: a label, the mesh request and the table."""

    label: str
    spec: ObjectSpec
    table: Table | None


def data_path() -> Path:
    """``pybullet_data``'s directory.

    Raises:
        ValidationError: ``objects`` when pybullet is not installed (``pip install eos_svc[objects]``).
    """
    try:
        import pybullet_data
    except ImportError:
        raise ValidationError(
            "objects", "the pybullet test objects need pybullet: pip install 'eos_svc[objects]'"
        ) from None
    return Path(pybullet_data.getDataPath())


def random_file(index: int) -> Path:
    """The mesh of random object ``index`` (0–999)."""
    if not 0 <= index < RANDOM_COUNT:
        raise ValidationError("ids", f"random object ids are 0-{RANDOM_COUNT - 1}, got {index}")
    return data_path() / "random_urdfs" / f"{index:03d}" / f"{index:03d}.obj"


def resting(label: str, file: Path, thin: float | None, rng: np.random.Generator) -> WorldObject | None:
    """The mesh of ``file`` scaled, turned and placed on the table (see the module doc); its
    thinnest extent ``thin`` m (None: drawn from ``rng``); None when too elongated."""
    unit = Mesh(file=str(file))
    axes = unit.principal_axes()  # columns, least inertia first: longest, middle, thinnest
    extents = np.ptp(np.asarray(unit.hull.vertices) @ axes, axis=0)
    longest, middle, thinnest = (float(e) for e in extents)
    top = min(THIN_MAX, LONGEST_MAX * thinnest / max(longest, middle))
    if top < THIN_MIN:
        return None
    width = float(rng.uniform(THIN_MIN, top)) if thin is None else thin
    scale = width / thinnest
    R = np.column_stack([axes[:, 0], axes[:, 2], axes[:, 1]]).T  # world ← local: x longest, y thin, z middle
    if np.linalg.det(R) < 0.0:
        R[2] *= -1.0
    lowest = float((np.asarray(unit.hull.vertices) @ R.T)[:, 2].min()) * scale
    roll, pitch, yaw = (float(a) for a in pin.rpy.matrixToRpy(R))
    position = (PLACE[0], PLACE[1], TABLE_HEIGHT - lowest + 1e-5)
    spec = ObjectSpec("mesh", {"file": str(file), "scale": scale}, position, (roll, pitch, yaw))
    return WorldObject(label, spec, Table(TABLE_HEIGHT))


def random_object(index: int) -> WorldObject | None:
    """Random object ``index`` resting on the table, its thinnest width drawn with seed ``index``
    (None: too elongated for the hand)."""
    return resting(f"random {index:03d}", random_file(index), None, np.random.default_rng(index))


def random_objects(ids: range) -> tuple[list[WorldObject], list[int]]:
    """The random objects of ``ids`` the hand can span, and the ids left out (too elongated)."""
    kept, left = [], []
    for i in ids:
        obj = random_object(i)
        (left.append(i) if obj is None else kept.append(obj))
    return kept, left


def named_objects() -> list[WorldObject]:
    """The mug, the duck and the teddy on the table, each at the middle of the hand's widths."""
    out = []
    for name, file in NAMED.items():
        obj = resting(name, data_path() / file, 0.5 * (THIN_MIN + THIN_MAX), np.random.default_rng(0))
        if obj is not None:
            out.append(obj)
    return out


def parse_ids(text: str) -> range:
    """``"A-B"`` (inclusive) or ``"A"`` as a range of random object ids."""
    try:
        lo, _, hi = text.partition("-")
        first, last = int(lo), int(hi or lo)
    except ValueError:
        raise ValidationError("ids", f"must be A-B or A (integers), got {text!r}") from None
    if not 0 <= first <= last < RANDOM_COUNT:
        raise ValidationError("ids", f"must satisfy 0 ≤ A ≤ B ≤ {RANDOM_COUNT - 1}, got {text!r}")
    return range(first, last + 1)


def thinnest_width(obj: WorldObject) -> float:
    """The placed object's extent along world y (m): its thinnest width."""
    mesh = Mesh(file=obj.spec.size["file"], scale=obj.spec.size["scale"])
    R = pin.rpy.rpyToMatrix(*obj.spec.rpy)
    return float(np.ptp((np.asarray(mesh.hull.vertices) @ R.T)[:, 1]))
