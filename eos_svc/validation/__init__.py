"""Grasp validation in Drake, an independent physics engine: ``validate_grasp(result)`` says
whether a plan's final grasp holds the object (``docs/validation.md``)."""

from eos_svc.validation.report import DIRECTIONS, DirectionOutcome, GraspValidation
from eos_svc.validation.simulation import SimulationError
from eos_svc.validation.validate import GraspSetup, grasp_setup, validate_grasp

__all__ = [
    "DIRECTIONS",
    "DirectionOutcome",
    "GraspSetup",
    "GraspValidation",
    "SimulationError",
    "grasp_setup",
    "validate_grasp",
]
