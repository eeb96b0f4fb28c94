"""The objects to grasp: one file per kind, each the one owner of everything about its kind.

- :mod:`~eos_svc.objects.base`: :class:`SurfaceObject`, the abstract kind.
- :mod:`~eos_svc.objects.sphere`, :mod:`~eos_svc.objects.ellipsoid`,
  :mod:`~eos_svc.objects.cylinder`, :mod:`~eos_svc.objects.capsule`,
  :mod:`~eos_svc.objects.box`: the primitives; :mod:`~eos_svc.objects.mesh`: a triangle mesh.
- :mod:`~eos_svc.objects.axial`: :class:`~eos_svc.objects.axial.AxialObject`, what the cylinder
  and the capsule share.
- :mod:`~eos_svc.objects.registry`: the kinds by name (:data:`KINDS`). See ``docs/objects.md``.
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
