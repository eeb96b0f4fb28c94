"""What the fingertips felt, as measurements for the shape fit.

A spherical fingertip of radius ``r`` touching the object at gap ≈ 0 tells two things:

- its **centre** ``c`` (from the hand's kinematics, exact up to the contact tolerance) lies at
  distance ``r`` from the surface: residual ``(sd(c) − r − gap₀) / σ_d``, with ``gap₀`` the
  mean gap at first touch and ``σ_d`` its spread;
- the **normal** there, from the tactile reading (the contact location on the fingertip,
  noisy by ``σ_t`` along the fingertip surface, i.e. by ``σ_t / r`` rad in direction):
  residual ``(∇sd(c) − n) / σ_n`` (the gradient of the signed distance at the tip centre is
  the outward normal at the closest surface point, defined near edges too).

A guarded probe that ran its whole travel without touching tells where the object is
**not**: every tip-centre sample ``f`` of its path has ``sd(f) ≥ r`` (a hinge residual).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

#: smallest σ of the normal used in the fit (rad): the model's own precision at zero noise
MIN_NORMAL_SIGMA = 2e-3
#: smallest σ of the tip-centre distance used in the fit (m)
MIN_DISTANCE_SIGMA = 2e-5


@dataclass
class Touches:
    """Contacts and free-space samples in world coordinates (m), not changed once made.

    Attributes:
        centres: (N, 3) fingertip-sphere centres at the contacts.
        normals: (N, 3) sensed outward object normals (unit).
        radii: (N,) fingertip radii.
        free: (M, 3) tip-centre samples of probes that touched nothing; ``free_radii`` (M,).
        tactile_noise: σ of the tactile contact location along the fingertip (m).
        kinematic_sigma: σ of a reported tip-centre position from the hand's joint encoders
            and link calibration (m; 0: exact kinematics, :mod:`eos_svc.world.joint_sensing`).
        contact_tolerance: a tip within this gap counts as touching (m); the gap at touch is
            taken as uniform on [0, tolerance].
    """

    centres: np.ndarray = field(default_factory=lambda: np.empty((0, 3)))
    normals: np.ndarray = field(default_factory=lambda: np.empty((0, 3)))
    radii: np.ndarray = field(default_factory=lambda: np.empty(0))
    free: np.ndarray = field(default_factory=lambda: np.empty((0, 3)))
    free_radii: np.ndarray = field(default_factory=lambda: np.empty(0))
    tactile_noise: float = 2e-4
    contact_tolerance: float = 1e-4
    kinematic_sigma: float = 0.0

    def __post_init__(self) -> None:
        self.centres = np.asarray(self.centres, dtype=float).reshape(-1, 3)
        n = np.asarray(self.normals, dtype=float).reshape(-1, 3)
        norms = np.linalg.norm(n, axis=1, keepdims=True)
        self.normals = n / np.where(norms > 0, norms, 1.0)
        self.radii = np.broadcast_to(np.asarray(self.radii, dtype=float), (len(self.centres),)).copy()
        self.free = np.asarray(self.free, dtype=float).reshape(-1, 3)
        self.free_radii = np.broadcast_to(np.asarray(self.free_radii, dtype=float), (len(self.free),)).copy()
        if len(self.normals) != len(self.centres):
            raise ValueError("touches: centres and normals must have the same length")

    @property
    def count(self) -> int:
        """Number of contacts."""
        return len(self.centres)

    @property
    def surface_points(self) -> np.ndarray:
        """The sensed contact points on the object, (N, 3): centre − r·normal."""
        out: np.ndarray = self.centres - self.radii[:, None] * self.normals
        return out

    @cached_property
    def points(self) -> np.ndarray:
        """The contacts' tip centres, then the free samples', (N + M, 3) (the fit's points)."""
        return np.concatenate([self.centres, self.free])

    @cached_property
    def sigma_distance(self) -> float:
        """σ of the tip-centre distance residual (m): the gap's spread at first touch, and the
        reported tip centre's own error (:attr:`kinematic_sigma`) when there is one."""
        gap = max(self.contact_tolerance / math.sqrt(12.0), MIN_DISTANCE_SIGMA)
        return gap if self.kinematic_sigma == 0.0 else math.hypot(gap, self.kinematic_sigma)

    @cached_property
    def gap_offset(self) -> float:
        """Mean gap at first touch (m)."""
        return 0.5 * self.contact_tolerance

    @cached_property
    def sigma_normal(self) -> float:
        """σ of each normal component (rad)."""
        r = float(np.mean(self.radii)) if len(self.radii) else 0.01
        return max(self.tactile_noise / r, MIN_NORMAL_SIGMA)
