"""A tactile sensor on a spherical fingertip: where on the fingertip the contact is.

The reading is expressed in the fingertip frame (origin at the sphere centre, m). Gaussian
noise of ``noise_std`` m per axis is added in the tangent plane of the fingertip surface and
the point is re-projected onto the sphere; an optional taxel ``pitch`` (m) then rounds each
coordinate to the nearest multiple of the pitch and re-projects onto the sphere. The rng is
seeded, so readings are reproducible.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._slots import slot_setters
from .geometry import tangent_basis, tangent_pair
from .hand import HandState, KinematicsError, UnknownNameError
from .scene import Contact

__all__ = ["TactileReading", "TactileSensor"]


@dataclass(frozen=True, slots=True)
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

    Args:
        noise_std: standard deviation of the tangential position noise, m (≥ 0).
        pitch: taxel pitch, m (> 0), or None for a continuous sensor.
        contact_tolerance: distances ≤ this (m) count as contact.
        rng: a numpy Generator, or a seed (an int or a ``SeedSequence``: the generator is made
            from it on the first noisy reading; a plan that never touches makes none), or None
            (fresh entropy).
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
            raise KinematicsError(
                "contact_tolerance", f"must be finite and ≥ 0 m, got {contact_tolerance!r}"
            )
        self.noise_std = float(noise_std)
        self.pitch = None if pitch is None else float(pitch)
        self.contact_tolerance = float(contact_tolerance)
        self._rng: np.random.Generator | None = None
        self._seed: np.random.SeedSequence | int | None = None
        self.rng = rng  # checked and kept (see the setter)

    @property
    def rng(self) -> np.random.Generator:
        """The position noise's generator (made from the seed given on first use)."""
        rng = self._rng
        if rng is None:
            rng = self._rng = np.random.default_rng(self._seed)
        return rng

    @rng.setter
    def rng(self, rng: np.random.Generator | np.random.SeedSequence | int | None) -> None:
        """A generator, or a seed (an int ≥ 0 or a ``SeedSequence``: the generator is made from
        it on first use), or None (fresh entropy on first use).

        Raises:
            KinematicsError: anything else.
        """
        if isinstance(rng, np.random.Generator):
            self._rng, self._seed = rng, None
            return
        if not (
            rng is None
            or isinstance(rng, np.random.SeedSequence)
            or (isinstance(rng, (int, np.integer)) and not isinstance(rng, bool) and rng >= 0)
        ):
            raise KinematicsError(
                "rng", f"must be a numpy Generator, a SeedSequence, an int ≥ 0 or None, got {rng!r}"
            )
        self._rng, self._seed = None, rng

    def read(self, state: HandState, contact: Contact) -> TactileReading:
        """The reading of ``contact.finger``'s sensor for this contact (state at the same q).

        The same numbers as :meth:`read_reference` (the plain numpy form; tested bit for bit):
        the numpy products and norms that decide the round-off are kept (``Rᵀ (p − c)``, the
        dot products of the norms), the element-wise arithmetic on the 3-vectors is done in
        floats (numpy costs µs per operation on them)."""
        hand = state.hand
        finger = contact.finger
        if finger not in hand.finger_names:
            raise UnknownNameError(
                "contact.finger", f"unknown finger {finger!r}; known: {hand.finger_names}"
            )
        r = hand.tip_radius(finger)
        M = state.data.oMf[hand.tip_frame_id(finger)]
        R = M.rotation
        p = R.T @ (np.asarray(contact.point_tip, dtype=float) - M.translation)
        norm = math.sqrt(p.dot(p))  # = np.linalg.norm(p): sqrt(p·p)
        if norm < 1e-12:  # degenerate: fall back on the contact normal
            p = R.T @ np.asarray(contact.normal, dtype=float)
            norm = -1.0
        s = r / norm
        px, py, pz = p.tolist()
        px, py, pz = px * s, py * s, pz * s  # p * (r / norm)
        distance = contact.distance
        in_contact = bool(distance <= self.contact_tolerance)
        if in_contact:
            if self.noise_std > 0.0:
                t1x, t1y, t1z, t2x, t2y, t2z = tangent_pair(px / r, py / r, pz / r)  # tangent_basis(p / r)
                g0, g1 = self.rng.normal(0.0, self.noise_std, size=2).tolist()
                px, py, pz = px + g0 * t1x + g1 * t2x, py + g0 * t1y + g1 * t2y, pz + g0 * t1z + g1 * t2z
                p = np.array((px, py, pz))
                s = r / math.sqrt(p.dot(p))  # p *= r / np.linalg.norm(p)
                px, py, pz = px * s, py * s, pz * s
            if self.pitch is not None:  # the plain form (numpy's rounding)
                p = np.round(np.array((px, py, pz)) / self.pitch) * self.pitch
                pn = float(np.linalg.norm(p))
                if pn > 1e-12:
                    p *= r / pn
                px, py, pz = p.tolist()
        reading: TactileReading = _new(TactileReading)  # slots filled directly (see _slots)
        _SR_FINGER(reading, finger)
        _SR_POINT(reading, np.array((px, py, pz)))
        _SR_NORMAL(reading, np.array((px / r, py / r, pz / r)))
        _SR_IN(reading, in_contact)
        _SR_DIST(reading, float(distance))
        return reading

    def read_reference(self, state: HandState, contact: Contact) -> TactileReading:
        """:meth:`read` in its plain numpy form (what the tests compare it with)."""
        hand = state.hand
        if contact.finger not in hand.finger_names:
            raise UnknownNameError(
                "contact.finger", f"unknown finger {contact.finger!r}; known: {hand.finger_names}"
            )
        r = hand.tip_radius(contact.finger)
        M = state.data.oMf[hand.tip_frame_id(contact.finger)]
        p = M.rotation.T @ (np.asarray(contact.point_tip, dtype=float) - M.translation)
        norm = float(np.linalg.norm(p))
        if norm < 1e-12:  # degenerate: fall back on the contact normal
            p = M.rotation.T @ np.asarray(contact.normal, dtype=float)
            norm = -1.0
        p = p * (r / norm)
        in_contact = bool(contact.distance <= self.contact_tolerance)
        if in_contact:
            if self.noise_std > 0.0:
                n = p / r
                t1, t2 = tangent_basis(n)
                g = self.rng.normal(0.0, self.noise_std, size=2)
                p = p + g[0] * t1 + g[1] * t2
                p *= r / np.linalg.norm(p)
            if self.pitch is not None:
                p = np.round(p / self.pitch) * self.pitch
                pn = float(np.linalg.norm(p))
                if pn > 1e-12:
                    p *= r / pn
        return TactileReading(contact.finger, p, p / r, in_contact, float(contact.distance))


_new = object.__new__
_SR_FINGER, _SR_POINT, _SR_NORMAL, _SR_IN, _SR_DIST = slot_setters(
    TactileReading, "finger", "point_tip", "normal_tip", "in_contact", "distance"
)


def read_sphere_tip(
    sensor: TactileSensor, contact: Contact, rotation: np.ndarray, n: tuple[float, ...], r: float
) -> TactileReading:
    """:meth:`TactileSensor.read` of a contact on a sphere tip of radius ``r`` (m), written with
    scalar arithmetic for the rolling step (``read`` spends ~100 µs in ``np.cross`` and friends on
    3-vectors): the same reading, the same noise model and random draws (tested equal).

    Args:
        rotation: the tip frame's world rotation (3×3) at the contact's configuration.
        n: the contact normal (object → tip) as three floats.
    """
    d = contact.distance
    if type(d) is not float:
        d = float(d)
    in_contact, px, py, pz = sphere_tip_point(sensor, d, rotation, n, r)
    reading: TactileReading = _new(TactileReading)  # slots filled directly (see _slots)
    _SR_FINGER(reading, contact.finger)
    _SR_POINT(reading, np.array((px, py, pz)))
    _SR_NORMAL(reading, np.array((px / r, py / r, pz / r)))
    _SR_IN(reading, in_contact)
    _SR_DIST(reading, d)
    return reading


def sphere_tip_point(
    sensor: TactileSensor, distance: float, rotation: np.ndarray, n: tuple[float, ...], r: float
) -> tuple[bool, float, float, float]:
    """:func:`read_sphere_tip`'s numbers without the :class:`TactileReading`: ``(in contact,
    the sensed point in the tip frame as three floats, m)`` for a contact at signed distance
    ``distance`` (m, a float) with normal ``n`` (object → tip, three floats) on a sphere tip of
    radius ``r`` (m) whose frame has the world rotation ``rotation``. Draws the sensor's noise
    (when in contact) as ``read`` does."""
    # p = Rᵀ (point_tip − c) = −r Rᵀ n on the sphere (point_tip = c − r n)
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = rotation.tolist()
    n0, n1, n2 = n
    px = -r * (n0 * r00 + n1 * r10 + n2 * r20)
    py = -r * (n0 * r01 + n1 * r11 + n2 * r21)
    pz = -r * (n0 * r02 + n1 * r12 + n2 * r22)
    in_contact = distance <= sensor.contact_tolerance  # a bool (floats)
    if in_contact:
        if sensor.noise_std > 0.0:
            t1x, t1y, t1z, t2x, t2y, t2z = tangent_pair(px / r, py / r, pz / r)
            g0, g1 = sensor.rng.normal(0.0, sensor.noise_std, size=2).tolist()
            px, py, pz = px + g0 * t1x + g1 * t2x, py + g0 * t1y + g1 * t2y, pz + g0 * t1z + g1 * t2z
            s = r / math.sqrt(px * px + py * py + pz * pz)
            px, py, pz = px * s, py * s, pz * s
        if sensor.pitch is not None:
            h = sensor.pitch
            px, py, pz = round(px / h) * h, round(py / h) * h, round(pz / h) * h
            pn = math.sqrt(px * px + py * py + pz * pz)
            if pn > 1e-12:
                px, py, pz = px * r / pn, py * r / pn, pz * r / pn
    return in_contact, px, py, pz
