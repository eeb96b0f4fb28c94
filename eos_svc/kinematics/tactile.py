"""A tactile sensor on a spherical fingertip: where on the fingertip the contact is (fingertip
frame, m), with seeded Gaussian noise in the tangent plane and an optional taxel pitch, each
re-projected onto the sphere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .geometry import tangent_pair
from .hand import HandState, KinematicsError, UnknownNameError
from .scene import Contact

__all__ = ["TactileReading", "TactileSensor"]


@dataclass(slots=True)
class TactileReading:
    """One reading of a fingertip sensor.

    Attributes:
        finger: finger name.
        point_tip: contact location in the fingertip frame, on the fingertip sphere, m.
        normal_tip: outward unit normal of the fingertip surface there (fingertip frame).
        in_contact: True when the signed distance is within the sensor's contact tolerance.
            When False the point is the noise-free nearest point (no measurement).
        distance: signed tip–object distance, m (from the contact query).
    """

    finger: str
    point_tip: np.ndarray
    normal_tip: np.ndarray
    in_contact: bool
    distance: float


class TactileSensor:
    """Tactile reading for a spherical fingertip from a :class:`~.scene.Contact`.

    ``noise_std``: σ of the tangential position noise, m; ``pitch``: taxel pitch, m (None:
    continuous); ``contact_tolerance``: distances ≤ this (m) count as contact; ``rng``: a numpy
    Generator, a seed (an int ≥ 0 or a ``SeedSequence``; the generator is made at the first noisy
    reading) or None (fresh entropy).
    """

    def __init__(
        self,
        noise_std: float = 2e-4,
        pitch: float | None = None,
        contact_tolerance: float = 1e-4,
        rng: np.random.Generator | np.random.SeedSequence | int | None = None,
    ) -> None:
        if not (math.isfinite(noise_std) and noise_std >= 0.0):
            raise KinematicsError("noise_std", f"must be finite and ≥ 0 m, got {noise_std!r}")
        if pitch is not None and not (math.isfinite(pitch) and pitch > 0.0):
            raise KinematicsError("pitch", f"must be finite and > 0 m or None, got {pitch!r}")
        if not (math.isfinite(contact_tolerance) and contact_tolerance >= 0.0):
            raise KinematicsError("contact_tolerance", f"must be finite and ≥ 0 m, got {contact_tolerance!r}")
        self.noise_std = float(noise_std)
        self.pitch = None if pitch is None else float(pitch)
        self.contact_tolerance = float(contact_tolerance)
        seed = isinstance(rng, (int, np.integer)) and not isinstance(rng, bool) and rng >= 0
        if not (rng is None or seed or isinstance(rng, (np.random.Generator, np.random.SeedSequence))):
            raise KinematicsError(
                "rng", f"must be a numpy Generator, a SeedSequence, an int ≥ 0 or None, got {rng!r}"
            )
        self._seed = rng
        self._rng = rng if isinstance(rng, np.random.Generator) else None

    @property
    def rng(self) -> np.random.Generator:
        """The position noise's generator (made from the seed on first use)."""
        if self._rng is None:
            self._rng = np.random.default_rng(self._seed)
        return self._rng

    def read(self, state: HandState, contact: Contact) -> TactileReading:
        """The reading of ``contact.finger``'s sensor for this contact (``state`` at the same q)."""
        hand = state.hand
        if contact.finger not in hand.finger_names:
            raise UnknownNameError(
                "contact.finger", f"unknown finger {contact.finger!r}; known: {hand.finger_names}"
            )
        rotation = state.data.oMf[hand.tip_frame_id(contact.finger)].rotation
        return self.read_tip(contact, rotation, hand.tip_radius(contact.finger))

    def read_tip(self, contact: Contact, rotation: np.ndarray, radius: float) -> TactileReading:
        """The reading of ``contact`` on a sphere tip of ``radius`` m whose frame has the world
        ``rotation`` (3×3): the contact point on the tip, ``−radius Rᵀ n``, moved by the noise in
        the tangent plane and re-projected on the sphere, then rounded to the taxel pitch."""
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = rotation.tolist()
        n0, n1, n2 = contact.normal.tolist()
        r = radius
        px = -r * (n0 * r00 + n1 * r10 + n2 * r20)
        py = -r * (n0 * r01 + n1 * r11 + n2 * r21)
        pz = -r * (n0 * r02 + n1 * r12 + n2 * r22)
        distance = float(contact.distance)
        in_contact = distance <= self.contact_tolerance
        if in_contact and self.noise_std > 0.0:
            t1x, t1y, t1z, t2x, t2y, t2z = tangent_pair(px / r, py / r, pz / r)
            g0, g1 = self.rng.normal(0.0, self.noise_std, size=2).tolist()
            px, py, pz = px + g0 * t1x + g1 * t2x, py + g0 * t1y + g1 * t2y, pz + g0 * t1z + g1 * t2z
            s = r / math.sqrt(px * px + py * py + pz * pz)
            px, py, pz = px * s, py * s, pz * s
        if in_contact and self.pitch is not None:
            h = self.pitch
            px, py, pz = round(px / h) * h, round(py / h) * h, round(pz / h) * h
            norm = math.sqrt(px * px + py * py + pz * pz)
            if norm > 1e-12:
                px, py, pz = px * r / norm, py * r / norm, pz * r / norm
        point = np.array((px, py, pz))
        return TactileReading(contact.finger, point, np.array((px / r, py / r, pz / r)), in_contact, distance)
