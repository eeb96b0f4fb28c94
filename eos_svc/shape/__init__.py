"""Knowing the object by touch: fit primitive classes to sensed contacts and choose one.

- :mod:`~eos_svc.shape.primitives`: signed distance and its gradient for each class
  (sphere, ellipsoid, cylinder, capsule, box) in the class's own frame, vectorised.
- :mod:`~eos_svc.shape.touches`: the measurements (fingertip-centre contacts with sensed
  normals, free-space samples) and their noise model.
- :mod:`~eos_svc.shape.fit`: least-squares fit of one class (scipy.optimize.least_squares).
- :mod:`~eos_svc.shape.selection`: fit every class, posterior over classes from BIC, the
  calibrated confidence and the postulated object in the request's JSON form.

Pure numpy/scipy (no Pinocchio, coal or Zenoh): testable offline on synthetic samples.
"""

from eos_svc.shape.fit import ClassFit, fit_class
from eos_svc.shape.selection import CLASSES, Postulate, select_class
from eos_svc.shape.touches import Touches

__all__ = ["CLASSES", "ClassFit", "Postulate", "Touches", "fit_class", "select_class"]
