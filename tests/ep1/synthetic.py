"""Closed-form rolling of a sphere fingertip on simple objects, independent of the hand.

Used to prove the estimator's sign convention without the Pinocchio hand: the tip
rolls without sliding (its material point at the contact has zero velocity,
``ċ = ω × (c − p)``), the contact point is the closest point of the object to the
tip centre, and the tactile reading is that point in the tip frame.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

Closest = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]  # c -> (p, n_out)


def sphere(R: float) -> Closest:
    def f(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = c / np.linalg.norm(c)
        return R * n, n

    return f


def plane() -> Closest:  # z = 0, outward +z
    def f(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return np.array([c[0], c[1], 0.0]), np.array([0.0, 0.0, 1.0])

    return f


def cylinder(r: float) -> Closest:  # axis = world z
    def f(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = np.array([c[0], c[1], 0.0])
        n /= np.linalg.norm(n)
        return np.array([r * n[0], r * n[1], c[2]]), n

    return f


def rodrigues(w: np.ndarray) -> np.ndarray:
    th = float(np.linalg.norm(w))
    if th < 1e-15:
        return np.eye(3)
    k = w / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def contact_frame(n_obj: np.ndarray) -> np.ndarray:
    """Columns x, y, z of the contact frame; z = fingertip normal = -n_obj."""
    z = -n_obj
    ref = np.array([0.0, 0.0, 1.0]) if abs(z[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(ref, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def roll(
    closest: Closest,
    p0: np.ndarray,
    n0: np.ndarray,
    r_f: float,
    omega_world: np.ndarray,
    T: float,
    steps: int = 2000,
) -> tuple[np.ndarray, np.ndarray]:
    """Roll for time T; return the tip-frame contact trajectory (steps+1, 3) and times."""
    c = p0 + r_f * n0
    Rt = np.eye(3)
    dt = T / steps
    out = [Rt.T @ (p0 - c)]
    for _ in range(steps):
        # midpoint integration of ċ = ω × (c − p), Ṙ = [ω] R
        p, _n = closest(c)
        cm = c + 0.5 * dt * np.cross(omega_world, c - p)
        pm, _n = closest(cm)
        c = c + dt * np.cross(omega_world, cm - pm)
        Rt = rodrigues(omega_world * dt) @ Rt
        p, _n = closest(c)
        out.append(Rt.T @ (p - c))
    return np.array(out), np.linspace(0.0, T, steps + 1)
