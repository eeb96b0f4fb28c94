"""Active touch's choice: a probe's predicted distance under each candidate (closed forms), and
the probe chosen where the candidates' surfaces differ most."""

from __future__ import annotations

import math

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest
from eos_svc.agents.planner import build_world
from eos_svc.agents.probe_choice import OFFSET, next_probes
from eos_svc.drivers.kinematic import KinematicDriver
from eos_svc.shape.probe_information import Candidate, choose, disagreement, hit_distances

TIP = 0.01  # tip radius (m)


def candidate(kind: str, half: list[float], centre=(0.0, 0.0, 0.0), probability: float = 0.5) -> Candidate:
    """A candidate of ``kind`` upright at ``centre`` with half sizes ``half`` and no spread."""
    orientation = {"sphere": 0, "box": 3, "cylinder": 2, "capsule": 2, "ellipsoid": 3}[kind]
    theta = np.array([*centre, *np.zeros(orientation), *np.log(half)])
    return Candidate(kind, probability, theta, np.eye(3), np.zeros((len(theta), len(theta))))


def rays_towards(centre: np.ndarray, directions: np.ndarray, distance: float):
    """Starts ``distance`` from ``centre`` moving back along each unit direction toward it."""
    starts = centre + distance * directions
    return starts, -directions, np.full(len(directions), 2 * distance), np.full(len(directions), TIP)


def test_hit_distances_match_closed_forms():
    # a sphere of radius R: a tip from distance D toward its centre touches after D − R − r
    sphere = candidate("sphere", [0.04])
    starts, dirs, travel, radius = rays_towards(np.zeros(3), np.eye(3), 0.2)
    t = hit_distances("sphere", sphere.members()[:1], np.eye(3), starts, dirs, travel, radius)
    np.testing.assert_allclose(t[0], 0.2 - 0.04 - TIP, atol=2e-4)
    # a line that passes the sphere by more than R + r touches nothing: its whole travel
    t = hit_distances(
        "sphere",
        sphere.members()[:1],
        np.eye(3),
        np.array([[0.2, 0.06, 0.0]]),
        np.array([[-1.0, 0.0, 0.0]]),
        np.array([0.4]),
        np.array([TIP]),
    )
    assert t[0, 0] == pytest.approx(0.4)


def test_the_probe_separating_a_box_from_a_short_cylinder_goes_through_the_corner():
    # a box 2a × 2a × 2h and the cylinder of radius a inscribed in it fit touches on the four
    # side faces' centres alike; a horizontal line through the centre at angle φ meets the
    # cylinder's offset surface (the tip centre's) at a + r from the centre and the box's at
    # (a + r)/cos φ on its face (φ ≤ 45° by symmetry), or where the line comes within r of the
    # vertical edge at (a, a): they differ most through the corner (φ = 45°), by (√2 − 1)·a
    a, h = 0.03, 0.02
    box, cylinder = candidate("box", [a, a, h]), candidate("cylinder", [a, h])
    angles = np.radians(np.arange(0.0, 91.0, 5.0))
    directions = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)
    starts, dirs, travel, radius = rays_towards(np.zeros(3), directions, 0.2)
    R = disagreement([box, cylinder], starts, dirs, travel, radius)
    variance = np.diag(R.T @ R)
    # two classes of equal probability: the mixture's variance is (Δt / 2)²
    phi = np.minimum(angles, np.pi / 2 - angles)
    u = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    on_face = (a + TIP) / np.cos(phi)
    uc = u @ np.array([a, a])
    on_edge = uc + np.sqrt(np.maximum(uc**2 - 2 * a * a + TIP**2, 0.0))  # the outer root: from outside
    box_hit = np.where((a + TIP) * np.tan(phi) <= a, on_face, on_edge)
    delta = box_hit - (a + TIP)
    np.testing.assert_allclose(variance, (delta / 2) ** 2, atol=1e-7)
    (best,) = choose(R, noise=2e-4, most=1, floor=0.0)
    assert math.degrees(angles[best]) == pytest.approx(45.0)
    assert 2 * math.sqrt(variance[best]) == pytest.approx((math.sqrt(2) - 1) * a, abs=3e-4)


def test_the_probe_separating_a_capsule_from_a_cylinder_goes_along_the_axis():
    # the same radius a and straight half length h: the capsule's dome reaches a past the
    # cylinder's flat end on the axis (a − a·(1 − cos) off it), the sides coincide
    a, h = 0.02, 0.03
    capsule, cylinder = candidate("capsule", [a, h]), candidate("cylinder", [a, h])
    tilts = np.radians(np.arange(0.0, 91.0, 10.0))  # from the axis (0) to across it (90°)
    directions = np.stack([np.sin(tilts), np.zeros_like(tilts), np.cos(tilts)], axis=1)
    starts, dirs, travel, radius = rays_towards(np.zeros(3), directions, 0.2)
    R = disagreement([capsule, cylinder], starts, dirs, travel, radius)
    spread = 2 * np.sqrt(np.diag(R.T @ R))
    (best,) = choose(R, noise=2e-4, most=1, floor=0.0)
    assert best == 0 and spread[0] == pytest.approx(a, abs=3e-4)
    assert spread[-1] == pytest.approx(0.0, abs=1e-6)


def test_greedy_choice_does_not_pick_the_same_information_twice():
    # two identical lines and a weaker independent one: after the first pick, its twin has
    # nothing left to tell, the independent one goes next
    R = np.array([[1.0, 1.0, 0.0], [0.0, 0.0, 0.5]])
    assert choose(R, noise=1e-3, most=2, floor=0.0) == [0, 2]
    assert choose(R, noise=1e-3, most=3, floor=0.01) == [0, 2]  # the twin is below the floor


def test_ep2_probes_where_a_box_and_a_cylinder_differ():
    # the hand's lines are along the world axes, on the bounds' faces at their centre and ±OFFSET
    # of the half sizes off it: between an upright box 2a × 2a × 2h and the cylinder inscribed in
    # it, a horizontal line offset by OFFSET·a meets the box's offset surface at a + r from the
    # centre plane and the cylinder's at √((a + r)² − (OFFSET·a)²): the chosen line is one of
    # those farthest off the centre, not the centre line (where both agree)
    a, h = 0.03, 0.025
    centre = np.array([0.21, 0.0, 0.0])
    spec = ObjectSpec("cylinder", {"radius": a, "length": 2 * h}, tuple(centre.tolist()))
    world = KinematicDriver(build_world(PlanRequest(obj=spec, seed=1)))
    candidates = [candidate(k, s, centre).to_dict() for k, s in (("box", [a, a, h]), ("cylinder", [a, h]))]
    (line,) = next_probes(world, candidates, (centre, np.array([a, a, h])), 1, 0.03)
    probe = next(line)
    assert abs(probe.direction[2]) < 1e-9  # horizontal
    across = probe.start - centre - ((probe.start - centre) @ probe.direction) * probe.direction
    assert np.linalg.norm(across[:2]) == pytest.approx(OFFSET * a, abs=1e-9)
    r = world.hand.tip_radius(probe.finger)
    expected = (a + r) - math.sqrt((a + r) ** 2 - (OFFSET * a) ** 2)
    R = disagreement(
        [Candidate.from_dict(c) for c in candidates],
        probe.start[None],
        probe.direction[None],
        np.array([probe.travel]),
        np.array([r]),
    )
    assert 2 * float(np.sqrt(np.sum(R * R))) == pytest.approx(expected, abs=3e-4)
