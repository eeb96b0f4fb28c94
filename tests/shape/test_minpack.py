"""Why a fit can differ from run to run in its last digits: scipy's MINPACK, not the fit's
numpy reference.

scipy 1.17's C MINPACK (``scipy/optimize/src/minpack.c``, ``qrfac``) recomputes a column's norm
when Householder updates have cancelled most of it as ``enorm(m - j, &a[(j + 1) + lda*k])``:
m − j elements from row j + 1, one more than the column holds (the Fortran original reads
m − j elements from row j + 1 counted from 1). For every column but the last that extra
element is the next column's first (the same in every run); for the last column it is the 8
bytes after the Jacobian scipy allocated — stale memory whenever the allocation's size leaves
slack in its malloc chunk (m·n even), whatever an earlier array left there. That norm decides
the pivot order of the next Householder steps, so ``leastsq``'s iterates — and a shape fit's
χ² and parameters — can depend on the process's allocation history: the compiled and the numpy
evaluations of a fit agree bit for bit (below), the least-squares driver around them does not.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import leastsq

from eos_svc.shape import Touches, fit


def _collinear_problem() -> tuple[np.ndarray, np.ndarray]:
    """A linear least-squares problem (52, 3) whose last column is, to 1e-9, a multiple of
    the first (the largest, pivoted first): after the first Householder step its norm is
    almost all cancelled, and qrfac recomputes it."""
    rng = np.random.default_rng(0)
    m, n = 52, 3  # m·n·8 = 1248 B: a 1264 B malloc chunk, 8 B of it past the array
    A = rng.normal(size=(m, n))
    A[:, 0] *= 10.0
    A[:, 2] = 0.3 * A[:, 0] + 1e-9 * rng.normal(size=m)
    return A, rng.normal(size=m)


def _solve_after_freeing(stale: float, A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """leastsq on ``A x ≈ b`` right after freeing a block of the Jacobian's malloc size whose
    last 8 bytes (past the Jacobian's (n, m) doubles) hold ``stale``: glibc hands that block to
    the next request of the size, the Jacobian scipy allocates."""
    block = np.full(A.size + 1, stale)
    del block
    x, *_ = leastsq(lambda x: A @ x - b, np.zeros(A.shape[1]), Dfun=lambda x: A.copy(), full_output=True)
    out: np.ndarray = x
    return out


def zero_row_case() -> str:
    """The fit's workaround (:func:`eos_svc.shape.fit._with_zero_row`, used when k is odd and
    m·k even): the same problem with one zero residual more gives the same iterates whatever
    the freed memory held. (Not compared with the unpadded solve after freeing zeros: whether
    that one read the freed block depends on the heap, the thing under test.)"""
    A, b = _collinear_problem()
    k = A.shape[1]
    assert k % 2 == 1 and A.size % 2 == 0

    def solve(stale: float) -> np.ndarray:
        for size in (A.size + 1, A.size + k + 1):  # the unpadded and the padded Jacobian's size
            block = np.full(size, stale)
            del block
        x, *_ = leastsq(
            fit._with_zero_row(lambda x: A @ x - b),
            np.zeros(k),
            Dfun=fit._with_zero_row(lambda x: A.copy()),
            full_output=True,
        )
        out: np.ndarray = x
        return out

    reference = _solve_after_freeing(0.0, A, b)
    # the bug first: unpadded, the freed memory's value changes the iterates (else there is
    # nothing to work around here: scipy fixed qrfac, or the freed block was not reused)
    if all(np.array_equal(_solve_after_freeing(1e3, A, b), reference) for _ in range(3)):
        return "skip: scipy's leastsq did not read the freed memory past its Jacobian here"
    padded = {solve(stale).tobytes() for stale in (0.0, 1e3, -3e5, 1.0, 0.0)}
    assert len(padded) == 1, "the padded solve depends on the memory past MINPACK's Jacobian"
    return "ok"


def _in_fresh_interpreter(call: str) -> None:
    """Run ``call`` (a case of this module) in a fresh interpreter, whose heap hands a freed
    block back to the next allocation of its size (after a whole test session it seldom does);
    skip when the case could not reproduce scipy's over-read there."""
    out = subprocess.run(
        [sys.executable, "-c", f"from tests.shape.test_minpack import *; print({call})"],
        cwd=Path(__file__).resolve().parents[2],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    verdict = out.stdout.strip().splitlines()[-1]
    if verdict.startswith("skip: "):
        pytest.skip(verdict[len("skip: ") :])
    assert verdict == "ok", verdict


def test_a_zero_row_makes_leastsq_independent_of_memory_past_its_jacobian():
    _in_fresh_interpreter("zero_row_case()")


def _place(a: np.ndarray, offset: int) -> np.ndarray:
    """A copy of ``a`` starting ``offset`` doubles past a 64-byte boundary."""
    raw = np.empty(a.size + 16)
    start = (-raw.ctypes.data % 64) // 8 + offset
    out = raw[start : start + a.size].reshape(a.shape)
    out[...] = a
    return out


def _touches(seed: int) -> Touches:
    """14 noisy contacts on an ellipsoid-like cloud and 5 free samples outside it (m)."""
    rng = np.random.default_rng(seed)
    n = 14
    u = rng.normal(size=(n, 3))
    normals = u / np.linalg.norm(u, axis=1, keepdims=True)
    centres = normals * np.array([0.04, 0.03, 0.05]) + rng.normal(scale=1e-3, size=(n, 3))
    return Touches(centres, normals, np.full(n, 0.008), 0.09 * normals[:5] * 1.5, np.full(5, 0.008))


@pytest.mark.parametrize("kind", tuple(fit.N_PARAMS))
def test_numpy_reference_is_independent_of_alignment(kind):
    """The fit's numpy evaluation (residuals and difference Jacobian at every start) gives the
    same bits whatever the 8-byte offset of its data from a 64-byte boundary (OpenBLAS's and
    numpy's vector loops could, in principle, sum in another order on unaligned data)."""
    touches = _touches(4)
    shared = fit.ClassStarts(touches)
    data = shared.fit_data
    for theta0, r0 in shared.of(kind):
        R0, J0, _ = fit._difference_evaluation_numpy(theta0, kind, r0, data)
        for offset in range(8):
            moved = dataclasses.replace(
                data,
                **{
                    f.name: _place(getattr(data, f.name), offset)
                    for f in dataclasses.fields(data)
                    if isinstance(getattr(data, f.name), np.ndarray)
                },
            )
            theta, rotation = _place(theta0, offset), _place(r0, offset)
            R, J, _ = fit._difference_evaluation_numpy(theta, kind, rotation, moved)
            assert np.array_equal(R, R0) and np.array_equal(J, J0)


def _random_touches(seed: int) -> Touches:
    """6–15 noisy contacts about an ellipsoid-like cloud and 6 free samples (m = 4·n + 6, even)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(6, 16))
    u = rng.normal(size=(n, 3))
    normals = u / np.linalg.norm(u, axis=1, keepdims=True)
    centres = normals * rng.uniform(0.02, 0.06, 3) + rng.normal(scale=2e-3, size=(n, 3))
    return Touches(centres, normals, np.full(n, 0.008), rng.normal(size=(6, 3)) * 0.1, np.full(6, 0.008))


def _leastsq_after_freeing(stale: float, sizes: tuple[int, ...]):
    """scipy's leastsq, called right after freeing blocks of ``sizes`` doubles whose last holds
    ``stale`` (the Jacobian's malloc size classes: the next allocation of the size is it)."""

    def call(*args, **kwargs):
        for size in sizes:
            block = np.full(size, stale)
            del block
        return leastsq(*args, **kwargs)

    return call


def fit_case(seed: int, kind: str, start: int) -> str:
    """Touches (m·k even) on which scipy's MINPACK, called as it is, ends elsewhere when the 8
    bytes past its Jacobian hold 1e3 instead of 0; the fit's Levenberg–Marquardt
    (:func:`~eos_svc.shape.fit.levenberg_marquardt`) ends at the same bits whatever they hold.
    (Not compared with the unpadded fit after freeing zeros: whether that one read the freed
    block depends on the heap, the thing under test.)"""
    touches = _random_touches(seed)
    m, k = fit.residual_count(touches), fit.N_PARAMS[kind]
    theta0, r0 = fit.ClassStarts(touches).of(kind)[start]
    assert (m * k) % 2 == 0 and k % 2 == 1
    sizes = (k * m + 1, k * (m + 1) + 1)

    def unpadded(stale: float) -> bytes:
        ev = fit._Evaluations(kind, r0, touches)
        x, *_ = _leastsq_after_freeing(stale, sizes[:1])(
            ev.residuals,
            theta0.copy(),
            Dfun=ev.jacobian,
            full_output=True,
            ftol=1e-8,
            xtol=1e-8,
            gtol=1e-8,
            maxfev=20,
        )
        return bytes(x.tobytes())

    if all(unpadded(1e3) == unpadded(0.0) for _ in range(5)):
        return "skip: scipy's MINPACK did not read past its Jacobian on these touches here"
    results = set()
    try:
        for stale in (0.0, 1e3, -3e5, 0.0):
            fit.leastsq = _leastsq_after_freeing(stale, sizes)  # type: ignore[attr-defined]
            x, _ = fit.levenberg_marquardt(theta0, kind, r0, touches, 20, fit._Evaluations(kind, r0, touches))
            results.add(x.tobytes())
    finally:
        fit.leastsq = leastsq  # type: ignore[attr-defined]
    assert len(results) == 1, "the fit depends on the memory past MINPACK's Jacobian"
    return "ok"


@pytest.mark.parametrize(("seed", "kind", "start"), [(1, "box", 1), (12, "cylinder", 0), (12, "cylinder", 3)])
def test_a_fit_is_independent_of_memory_past_minpacks_jacobian(seed, kind, start):
    _in_fresh_interpreter(f"fit_case({seed}, {kind!r}, {start})")
