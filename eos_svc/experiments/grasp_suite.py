"""The objects of ``eos experiment grasps``: a fixed suite of every class and the poses that
matter, a seeded held-back suite and random draws (``docs/validation.md``).
"""

import math
from typing import NamedTuple

import numpy as np

from eos_svc.agents.planner import default_hand
from eos_svc.schema.request import ObjectSpec

#: sphere diameters of the fixed suite, as d/h
SPHERE_RATIOS = (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95)
#: seed of the held-back suite's generator
HELD_BACK_SEED = 20260
#: roll, pitch, yaw (rad) putting a cylinder's or capsule's local z axis …
POSES: dict[str, tuple[float, float, float]] = {
    "upright": (0.0, 0.0, 0.0),  # … along world z
    "across": (math.pi / 2, 0.0, 0.0),  # … along world y (across the approach)
    "along": (0.0, math.pi / 2, 0.0),  # … along world x (the approach)
    "angled": (math.pi / 2 - math.radians(30), 0.0, math.radians(45)),  # … 45° in x-y, 30° up
}
#: box aspect ratios (full edges x, y, z in m) and the yaw angles (deg) each is planned at
BOXES: dict[str, tuple[float, float, float]] = {
    "cube 50": (0.05, 0.05, 0.05),
    "plate 60x60x30": (0.06, 0.06, 0.03),
    "bar 30x30x80": (0.03, 0.03, 0.08),
}
BOX_YAWS_DEG = (0.0, 30.0, 60.0)


class SuiteObject(NamedTuple):
    """One object of a suite: a readable label, the object and, drawn at random, its plan seed."""

    label: str
    spec: ObjectSpec
    seed: int | None = None


def fixed_suite() -> list[SuiteObject]:
    """The fixed suite (29 objects), all at the default object position."""
    p = ObjectSpec().position  # the default request's
    h = default_hand().hand_height
    out = [
        SuiteObject(f"sphere d/h {r:.2f}", ObjectSpec("sphere", {"radius": 0.5 * r * h}, p))
        for r in SPHERE_RATIOS
    ]
    for label, radii in (
        ("ellipsoid long x", (0.04, 0.03, 0.025)),
        ("ellipsoid long y", (0.025, 0.04, 0.03)),
        ("ellipsoid long z", (0.025, 0.03, 0.04)),
    ):
        out.append(SuiteObject(label, ObjectSpec("ellipsoid", {"radii": radii}, p)))
    for shape, size in (
        ("cylinder", {"radius": 0.02, "length": 0.08}),
        ("capsule", {"radius": 0.02, "length": 0.05}),
    ):
        for pose, rpy in POSES.items():
            out.append(SuiteObject(f"{shape} {pose}", ObjectSpec(shape, size, p, rpy)))
    for name, edges in BOXES.items():
        for yaw in BOX_YAWS_DEG:
            spec = ObjectSpec("box", {"size": edges}, p, (0, 0, math.radians(yaw)))
            out.append(SuiteObject(f"box {name} yaw {yaw:.0f}", spec))
    return out


def quick_suite() -> list[SuiteObject]:
    """A small subset of the fixed suite: one object per class."""
    wanted = {
        "sphere d/h 0.50",
        "ellipsoid long z",
        "cylinder across",
        "capsule upright",
        "box cube 50 yaw 30",
    }
    return [o for o in fixed_suite() if o.label in wanted]


def held_back_suite(per_class: int = 3, seed: int = HELD_BACK_SEED) -> list[SuiteObject]:
    """``per_class`` objects of every class with sizes, orientations and positions drawn from a
    seeded generator (uniform ranges; positions within ±1 cm of the default)."""
    rng = np.random.default_rng(seed)
    h = default_hand().hand_height
    base = np.asarray(ObjectSpec().position)
    out = []

    def position() -> tuple[float, float, float]:
        x, y, z = base + rng.uniform(-0.01, 0.01, 3)
        return (round(float(x), 4), round(float(y), 4), round(float(z), 4))

    def mm(lo: float, hi: float) -> float:
        return round(float(rng.uniform(lo, hi)), 4)

    for i in range(per_class):
        r = mm(0.25, 0.9) * h / 2
        spec = ObjectSpec("sphere", {"radius": round(r, 4)}, position())
        out.append(SuiteObject(f"hb sphere {i} r{r * 1000:.0f}", spec))
    for i in range(per_class):
        radii = tuple(mm(0.018, 0.042) for _ in range(3))
        rpy = (0.0, 0.0, mm(-math.pi / 2, math.pi / 2))
        spec = ObjectSpec("ellipsoid", {"radii": radii}, position(), rpy)
        out.append(SuiteObject(f"hb ellipsoid {i}", spec))
    for shape in ("cylinder", "capsule"):
        for i in range(per_class):
            size = {"radius": mm(0.014, 0.028), "length": mm(0.03, 0.08)}
            rpy = (mm(0.0, math.pi / 2), 0.0, mm(-math.pi / 2, math.pi / 2))
            out.append(SuiteObject(f"hb {shape} {i}", ObjectSpec(shape, size, position(), rpy)))
    for i in range(per_class):
        edges = tuple(mm(0.025, 0.07) for _ in range(3))
        yaw = (0.0, 0.0, mm(0.0, math.pi / 2))
        out.append(SuiteObject(f"hb box {i}", ObjectSpec("box", {"size": edges}, position(), yaw)))
    return out


#: half-widths (m) of the box around the default position a random draw places objects in
DRAW_POSITION_SPREAD = (0.10, 0.12, 0.12)
#: the classes a random draw chooses from, uniformly
DRAW_CLASSES = ("sphere", "ellipsoid", "cylinder", "capsule", "box")


def random_draw(
    count: int, draw_seed: int, sizes: tuple[float, float] = (0.15, 0.50), span: float | None = None
) -> list[SuiteObject]:
    """``count`` objects from a seeded generator (``draw_seed``), none filtered (admission
    decides): the class uniform over :data:`DRAW_CLASSES`; every full width (a radius or half a
    length: half of one) uniform in ``sizes`` (low, high) × ``span`` (m; default hand3x3's span,
    as admission measures it); a uniformly random orientation; the position uniform in the
    default position ± :data:`DRAW_POSITION_SPREAD`; one plan seed each."""
    from scipy.spatial.transform import Rotation

    from eos_svc.world.admission import hand_span

    scale = hand_span(default_hand()) if span is None else span
    rng = np.random.default_rng(draw_seed)
    base, spread = np.asarray(ObjectSpec().position), np.asarray(DRAW_POSITION_SPREAD)
    out = []

    def width() -> float:
        return round(float(rng.uniform(*sizes)) * scale, 4)

    for i in range(count):
        shape = DRAW_CLASSES[int(rng.integers(len(DRAW_CLASSES)))]
        if shape == "sphere":
            size: dict = {"radius": round(width() / 2, 4)}
        elif shape == "ellipsoid":
            size = {"radii": tuple(round(width() / 2, 4) for _ in range(3))}
        elif shape in ("cylinder", "capsule"):
            size = {"radius": round(width() / 2, 4), "length": width()}
        else:
            size = {"size": tuple(width() for _ in range(3))}
        rpy = Rotation.random(random_state=rng).as_euler("xyz")
        position = base + rng.uniform(-spread, spread)
        seed = int(rng.integers(1, 2**31 - 1))
        spec = ObjectSpec(
            shape,
            size,
            tuple(round(float(v), 4) for v in position),  # type: ignore[arg-type]
            tuple(round(float(v), 4) for v in rpy),  # type: ignore[arg-type]
        )
        out.append(SuiteObject(f"draw {draw_seed}:{i} {shape}", spec, seed))
    return out
