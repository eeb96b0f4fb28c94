"""The rolling QP's solve paths and its error.

- :func:`min_norm_within_bounds` — closed form: the minimum-W-norm solution of the equalities
  (LAPACK ``dgels``), taken when it meets the bounds (then it is the QP's optimum);
- :func:`cached_osqp` — OSQP, set up once per thread for a problem structure, then updated and
  warm-started by the caller through the extension object (no wrapper glue per call);
- :func:`solve_with_backend` — any installed qpsolvers backend, by name.

A failed or infeasible QP raises :class:`RollingQPError` carrying a copy of the problem.
"""

from __future__ import annotations

import copy
import operator
import threading
from typing import Any

import numpy as np
import osqp
import qpsolvers
import scipy.sparse as sp
from scipy.linalg import lapack

from eos_svc.errors import ComputationError

__all__ = [
    "RollingQPError",
    "available_solvers",
    "cached_osqp",
    "min_norm_within_bounds",
    "solve_with_backend",
]

_DGELS = lapack.dgels
_LE = operator.le
_OSQP_CACHE = threading.local()


def available_solvers() -> list[str]:
    """Installed qpsolvers backends usable by the rolling QP (besides its own OSQP path)."""
    return list(qpsolvers.available_solvers)


class RollingQPError(ComputationError):
    """The rolling QP failed (infeasible, not solved, bad output).

    Attributes:
        problem: a copy of the :class:`qpsolvers.Problem` that failed.
        solver: backend name; ``status``: the backend's status text.
    """

    def __init__(self, message: str, problem: qpsolvers.Problem, solver: str, status: str) -> None:
        super().__init__(f"rolling QP ({solver}): {message} [status: {status}]")
        self.problem = problem
        self.solver = solver
        self.status = status


def min_norm_within_bounds(
    C: np.ndarray,
    b_ext: np.ndarray,
    wscale: np.ndarray | None,
    Cw: np.ndarray,
    lb_tol: list[float],
    ub_tol: list[float],
) -> tuple[np.ndarray, list[float]] | None:
    """The closed-form solve path: the minimum-W-norm solution of the equalities ``C q̇ = b``
    (one LAPACK ``dgels``), when it lies within the bounds — it is then the QP's optimum (the
    bounds are inactive); else None (a bound active, a rank-deficient or over-determined
    system: the caller asks a QP backend).

    Args:
        C: the 6×nx equality rows. b_ext: ``b`` followed by ``nx − 6`` ignored entries (dgels
            wants max(6, nx) rows). wscale: ``W^-1/2`` (diagonal, as a vector) or None for
            W = I; Cw: a 6×nx buffer for ``C W^-1/2``. lb_tol, ub_tol: the bounds widened by
            the solver tolerance, as floats.

    Returns:
        The solution as an array and as floats.
    """
    if C.shape[1] < 6:
        return None  # over-determined equalities: the backend decides
    if wscale is None:
        A = C
    else:
        A = Cw
        np.multiply(C, wscale, out=A)
    _, x, info = _DGELS(A, b_ext)
    if info != 0:
        return None  # rank-deficient
    # dgels' solution has max(6, nx) = nx rows; x = W^-1/2 z with z the minimum-norm solution
    if wscale is not None:
        x = x * wscale
    xs: list[float] = x.tolist()
    # Taken when within the bounds to OSQP's own tolerance eps (lb_tol = lb − eps, ub_tol =
    # ub + eps): OSQP's solutions meet the bounds only to ≈ eps·(1 + |q̇|) too (rolling at the
    # wrist's velocity limit puts the unconstrained optimum a few 1e-8 rad/s beyond it; OSQP
    # returns a point within ~1e-6 of the unconstrained optimum there, while clamping exactly
    # would move the finger by ~1e-3 rad/s — the problem is nearly degenerate in that direction).
    # lo <= x_i <= hi for every i (False on NaN), the loop in C
    if all(map(_LE, lb_tol, xs)) and all(map(_LE, xs, ub_tol)):
        return x, xs
    return None


def solve_with_backend(problem: qpsolvers.Problem, solver: str) -> tuple[np.ndarray, int]:
    """The generic solve path: any installed qpsolvers backend on the problem; (x, 0).

    Raises:
        RollingQPError: no finite solution (with a copy of the problem).
    """
    sol = qpsolvers.solve_problem(problem, solver=solver)
    if not sol.found or sol.x is None or not np.all(np.isfinite(sol.x)):
        raise RollingQPError(
            "no solution found", copy.deepcopy(problem), solver, str(sol.extras or "not found")
        )
    return sol.x, 0


def cached_osqp(
    nx: int,
    eps: float,
    check_termination: int,
    P: np.ndarray,
    qlin: np.ndarray,
    Ax: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
) -> tuple[Any, Any]:
    """The OSQP solve path: an OSQP solver for a rolling QP's structure, set up once per thread
    and reused; returns (the ``osqp.OSQP`` object, its extension object).

    Every rolling QP with ``nx`` variables has the same sparsity ([C; I], C dense 6×nx;
    P diagonal), so one set-up serves every roll of every EP1 run; the caller then
    overwrites all the data (q, l, u, P, A). Thread-local: OSQP objects are not shared
    between threads (the service plans concurrently).
    """
    key = (nx, eps, check_termination)
    cache: dict = getattr(_OSQP_CACHE, "solvers", None) or {}
    _OSQP_CACHE.solvers = cache
    if key not in cache:
        # column j of [C; I] holds rows 0..5 (C) and 6 + j (the bound row), in this order
        indices = np.concatenate([np.r_[0:6, 6 + j] for j in range(nx)]).astype(np.int32)
        A = sp.csc_matrix((Ax.copy(), indices, np.arange(0, 7 * nx + 1, 7)), shape=(6 + nx, nx))
        s = osqp.OSQP(algebra="builtin")  # naming it skips a per-object import probe (~1 ms)
        s.setup(
            sp.csc_matrix(np.triu(P)),
            qlin,
            A,
            lower,
            upper,
            eps_abs=eps,
            eps_rel=eps,
            eps_prim_inf=1e-12,
            eps_dual_inf=1e-12,
            warm_starting=True,
            polishing=False,
            verbose=False,
            max_iter=20000,
            check_termination=check_termination,
            scaling=0,  # small, well-scaled problem: no re-scaling on every update
            adaptive_rho=False,
            rho=0.05,
        )
        # The extension object behind osqp.OSQP: update/solve without the wrapper's
        # per-call Python glue (np.maximum on l/u, derivative cache, info namespace).
        cache[key] = (s, s._solver)
    return cache[key]
