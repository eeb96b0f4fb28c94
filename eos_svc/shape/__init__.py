"""Knowing the object by touch: fit the object kinds to sensed contacts and choose one.

- :mod:`~eos_svc.shape.touches`: the measurements (fingertip-centre contacts with sensed
  normals, free-space samples) and their noise model.
- :mod:`~eos_svc.shape.starts`: where each kind's fit starts.
- :mod:`~eos_svc.shape.fit`: least-squares fit of one kind on its signed distance
  (scipy.optimize.least_squares; the distances are the kinds' own, :mod:`eos_svc.objects`).
- :mod:`~eos_svc.shape.selection`: fit every kind, posterior over kinds from BIC, the
  calibrated confidence and the postulated object in the request's JSON form.
- :mod:`~eos_svc.shape.probe_information`: the candidate postulates' predicted touches along
  a probe's line, and the probes of largest expected information (active touch).
"""

from eos_svc.shape.fit import ClassFit, fit_class
from eos_svc.shape.selection import CLASSES, Postulate, select_class
from eos_svc.shape.touches import Touches

__all__ = ["CLASSES", "ClassFit", "Postulate", "Touches", "fit_class", "select_class"]
