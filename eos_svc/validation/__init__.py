"""Grasp validation in Drake, an independent physics engine.

    from eos_svc.agents import PlanRequest, plan
    from eos_svc.validation import validate_grasp
    result = plan(PlanRequest())
    check = validate_grasp(result)            # GraspValidation
    check.held, check.displacement_m          # True, {"+x": 0.0001, ...}
    result = result.with_validation(check)    # PlanResult.validation = check.to_dict()

See ``docs/validation.md`` for what is modelled and what is not.
"""

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
