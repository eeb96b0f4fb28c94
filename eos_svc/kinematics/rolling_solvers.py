"""The solver of the rolling QP (:func:`~eos_svc.kinematics.rolling_problem.step_qp`): the
equalities' minimum-``W``-norm solution (:func:`equality_optimum`) when it lies within the bounds,
else a qpsolvers backend by name (OSQP by default); a failed QP raises :class:`RollingQPError`.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import qpsolvers
from scipy.linalg import lapack

from eos_svc.errors import ComputationError

from .rolling_problem import StepQP

__all__ = ["BOUND_TOLERANCE", "RollingQPError", "equality_optimum", "solve_rolling_qp"]

#: tolerance on the bounds, rad/s or m/s, of the closed form (OSQP's own tolerance below)
BOUND_TOLERANCE = 1e-7

#: settings per backend (the rest: the backend's defaults)
BACKEND_SETTINGS: dict[str, dict[str, Any]] = {
    "osqp": {"eps_abs": 1e-7, "eps_rel": 1e-7, "polishing": False, "max_iter": 20000, "raise_error": False},
}


class RollingQPError(ComputationError):
    """The rolling QP failed (infeasible, not solved): the :class:`qpsolvers.Problem`, the
    backend's name and its status text."""

    def __init__(self, message: str, problem: qpsolvers.Problem, solver: str, status: str) -> None:
        super().__init__(f"rolling QP ({solver}): {message} [status: {status}]")
        self.problem = problem
        self.solver = solver
        self.status = status


def equality_optimum(qp: StepQP, tolerance: float = BOUND_TOLERANCE) -> np.ndarray | None:
    """``argmin ½ xᵀ W x`` subject to ``A x = b`` (W = diag(weights)), ``x = W⁻¹Aᵀ (A W⁻¹ Aᵀ)⁻¹ b``,
    when it lies within ``[lb − tolerance, ub + tolerance]``: it is then the optimum of the whole QP
    (no bound is active). None when a bound would be violated or ``A`` has not full row rank."""
    A = qp.A
    A_scaled = A / qp.weights  # A W⁻¹
    # ndarray.dot rather than @: the same product, half the call overhead on these 6×n arrays
    _, y, info = lapack.dposv(A_scaled.dot(A.T), qp.b)
    if info != 0:
        return None
    x: np.ndarray = y.dot(A_scaled)  # W⁻¹Aᵀ y
    # the smallest slack to either bound, ≥ −tolerance (False on NaN)
    return x if np.minimum.reduce(np.minimum(x - qp.lb, qp.ub - x)) >= -tolerance else None


def solve_rolling_qp(qp: StepQP, solver: str = "osqp", closed_form: bool = True) -> tuple[np.ndarray, bool]:
    """The joint velocities that solve ``qp`` and whether the closed form gave them
    (:func:`equality_optimum` when ``closed_form`` and no bound is active, else the qpsolvers
    backend ``solver``); :class:`RollingQPError` when there is no finite solution."""
    if closed_form:
        x = equality_optimum(qp)
        if x is not None:
            return x, True
    problem = qp.problem()
    if (qp.lb > qp.ub).any():
        raise RollingQPError("joint limits leave no feasible velocity", problem, solver, "infeasible bounds")
    with warnings.catch_warnings():  # dense matrices converted for OSQP; OSQP's own status warning
        warnings.simplefilter("ignore")
        sol = qpsolvers.solve_problem(problem, solver=solver, **BACKEND_SETTINGS.get(solver, {}))
    if not sol.found or sol.x is None or not np.isfinite(sol.x).all():
        status = getattr(sol.extras.get("info"), "status", "not found")
        raise RollingQPError("no solution found", problem, solver, str(status))
    return sol.x, False
