"""Knowing the object by touch: the touches (:mod:`~eos_svc.shape.touches`), the fits' starts
(:mod:`~eos_svc.shape.starts`), the least-squares fit of one kind (:mod:`~eos_svc.shape.fit`)
and the choice of kind with its confidence (:mod:`~eos_svc.shape.selection`).
"""

from eos_svc.shape.fit import ClassFit, fit_class
from eos_svc.shape.selection import CLASSES, Postulate, select_class
from eos_svc.shape.touches import Touches

__all__ = ["CLASSES", "ClassFit", "Postulate", "Touches", "fit_class", "select_class"]
