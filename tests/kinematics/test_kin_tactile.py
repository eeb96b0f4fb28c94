"""Tactile sensor: location on the fingertip in the tip frame, tangential Gaussian noise,
taxel pitch, seeded reproducibility."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from eos_svc.kinematics import HandModel, HandState, KinematicsError, Scene, TactileSensor, UnknownNameError
from eos_svc.objects import Sphere


def _touching(hand: HandModel, gap: float = 0.0) -> tuple[Scene, HandState]:
    q = hand.neutral()
    q[hand.finger_q_index("finger1")] = 0.4
    st = hand.state(q)
    c = st.tip_position("finger1")
    d = np.array([1.0, 0.0, -1.0]) / np.sqrt(2)  # object ahead and below the tip
    obj = Sphere(0.03, pin.SE3(np.eye(3), c + (0.04 + gap) * d))
    return Scene(hand, obj), st


def test_noise_free_reading_is_the_contact_in_tip_frame(hand: HandModel) -> None:
    scene, st = _touching(hand)
    con = scene.contact(st, "finger1")
    reading = TactileSensor(noise_std=0.0, rng=0).read(st, con)
    M = st.tip_placement("finger1")
    assert reading.in_contact and reading.finger == "finger1"
    assert np.allclose(M.act(reading.point_tip), con.point_tip, atol=1e-12)
    assert np.linalg.norm(reading.point_tip) == pytest.approx(0.01)
    assert np.allclose(reading.normal_tip, reading.point_tip / 0.01)
    assert np.allclose(M.rotation @ reading.normal_tip, -con.normal, atol=1e-9)
    assert reading.distance == pytest.approx(con.distance)


def test_noise_is_tangential_gaussian_and_seeded(hand: HandModel) -> None:
    scene, st = _touching(hand)
    con = scene.contact(st, "finger1")
    clean = TactileSensor(noise_std=0.0).read(st, con).point_tip
    sensor = TactileSensor(noise_std=2e-4, rng=42)
    pts = np.array([sensor.read(st, con).point_tip for _ in range(2000)])
    assert np.allclose(np.linalg.norm(pts, axis=1), 0.01)  # re-projected onto the sphere
    n = clean / 0.01
    tang = (pts - clean) - np.outer((pts - clean) @ n, n)
    std = np.sqrt(np.mean(np.sum(tang**2, axis=1)) / 2)
    assert std == pytest.approx(2e-4, rel=0.1)
    assert np.linalg.norm(np.mean(pts - clean, axis=0)) < 2e-5
    again = TactileSensor(noise_std=2e-4, rng=42)
    assert np.array_equal(again.read(st, con).point_tip, pts[0])


@pytest.mark.parametrize("seed", [42, np.random.SeedSequence(7, spawn_key=(1,))])
def test_a_seeded_sensor_makes_its_generator_at_its_first_noisy_reading(
    hand: HandModel, seed: object
) -> None:
    scene, st = _touching(hand)
    con = scene.contact(st, "finger1")
    lazy = TactileSensor(noise_std=2e-4, rng=seed)  # type: ignore[arg-type]
    assert lazy._rng is None  # nothing made yet
    TactileSensor(noise_std=0.0, rng=seed).read(st, con)  # type: ignore[arg-type]
    eager = TactileSensor(noise_std=2e-4, rng=np.random.default_rng(seed))  # type: ignore[arg-type]
    for _ in range(3):
        assert np.array_equal(lazy.read(st, con).point_tip, eager.read(st, con).point_tip)
    assert lazy._rng is not None


def test_taxel_pitch_quantizes(hand: HandModel) -> None:
    scene, st = _touching(hand)
    con = scene.contact(st, "finger1")
    pitch = 2e-3
    sensor = TactileSensor(noise_std=1e-4, pitch=pitch, rng=1)
    readings = {tuple(np.round(sensor.read(st, con).point_tip, 12)) for _ in range(200)}
    assert 1 <= len(readings) < 20  # a handful of taxels, not a continuum
    for p in readings:
        assert np.linalg.norm(p) == pytest.approx(0.01)


def test_not_in_contact(hand: HandModel) -> None:
    scene, st = _touching(hand, gap=0.01)
    con = scene.contact(st, "finger1")
    r = TactileSensor(rng=0).read(st, con)
    assert not r.in_contact and r.distance == pytest.approx(0.01)


def test_bad_parameters(hand: HandModel) -> None:
    for bad_seed in (-1, 1.5, True, "7"):
        with pytest.raises(KinematicsError, match="rng"):  # at construction, not at the first reading
            TactileSensor(rng=bad_seed)  # type: ignore[arg-type]
    sensor = TactileSensor(rng=np.random.default_rng(5))  # a generator given is the one used
    assert np.array_equal(sensor.rng.random(3), np.random.default_rng(5).random(3))
    with pytest.raises(KinematicsError, match="noise_std"):
        TactileSensor(noise_std=-1.0)
    with pytest.raises(KinematicsError, match="pitch"):
        TactileSensor(pitch=0.0)
    with pytest.raises(KinematicsError, match="contact_tolerance"):
        TactileSensor(contact_tolerance=float("nan"))
    scene, st = _touching(hand)
    con = scene.contact(st, "finger1")
    bad = type(con)("finger7", con.distance, con.point_tip, con.point_object, con.normal)
    with pytest.raises(UnknownNameError, match="finger7"):
        TactileSensor().read(st, bad)
