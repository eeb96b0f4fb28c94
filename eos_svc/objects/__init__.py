"""The objects to grasp: one file per kind, each the one owner of everything about its kind
(:mod:`~eos_svc.objects.base` the abstract kind, :mod:`~eos_svc.objects.registry` the kinds by
name). See ``docs/objects.md``.
"""

from eos_svc.objects.base import CurvatureUndefinedError, ObjectSizeError, SurfaceObject
from eos_svc.objects.box import Box
from eos_svc.objects.capsule import Capsule
from eos_svc.objects.cylinder import Cylinder
from eos_svc.objects.ellipsoid import Ellipsoid
from eos_svc.objects.mesh import Mesh
from eos_svc.objects.registry import FITTED_KINDS, KINDS, from_dict, kind_of, make
from eos_svc.objects.sphere import Sphere

__all__ = [
    "FITTED_KINDS",
    "KINDS",
    "Box",
    "Capsule",
    "CurvatureUndefinedError",
    "Cylinder",
    "Ellipsoid",
    "Mesh",
    "ObjectSizeError",
    "Sphere",
    "SurfaceObject",
    "from_dict",
    "kind_of",
    "make",
]
