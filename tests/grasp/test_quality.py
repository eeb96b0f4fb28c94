"""Grasp quality (eos_svc.grasp.quality) against closed forms and invariances."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from eos_svc.grasp.quality import (
    GraspQuality,
    contacts_quality,
    epsilon_of_wrenches,
    grasp_quality,
    primitive_wrenches,
)


def equator(n: int, radius: float = 1.0, phase: float = 0.0) -> np.ndarray:
    """``n`` evenly spaced points on a sphere's equator (also the outward normals / radius)."""
    a = phase + 2.0 * np.pi * np.arange(n) / n
    return radius * np.stack([np.cos(a), np.sin(a), np.zeros(n)], axis=1)


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


# --- closed forms -----------------------------------------------------------------------
@pytest.mark.parametrize("mu", [0.05, 0.2, 0.5, 1.0, 2.0])
def test_planar_antipodal_disc_closed_form(mu):
    """Two antipodal contacts on a disc of radius r, L = r: the wrench hull is a tetrahedron
    with vertices (∓1, ±μ, ±μ); its inscribed radius is μ / √(2 + μ²)."""
    r = 0.03
    q = grasp_quality([[r, 0.0], [-r, 0.0]], [[1.0, 0.0], [-1.0, 0.0]], [0.0, 0.0], mu, torque_scale=r)
    assert q.force_closure and q.dimension == 3 and q.rank == 3 and q.edges == 2
    assert q.epsilon == pytest.approx(mu / math.sqrt(2.0 + mu * mu), rel=1e-9)


def test_planar_antipodal_without_friction_is_not_closure():
    q = grasp_quality([[1.0, 0.0], [-1.0, 0.0]], [[1.0, 0.0], [-1.0, 0.0]], [0.0, 0.0], 0.0)
    assert not q.force_closure and q.epsilon == 0.0 and q.rank == 1


def test_planar_non_antipodal_needs_enough_friction():
    """Contacts at angles 0 and 180°−2β on a disc: the line between them makes the angle β with
    each normal, so closure needs μ > tan β (Nguyen's planar antipodal test)."""
    beta = math.radians(20.0)
    a = np.array([0.0, math.pi - 2.0 * beta])
    p = np.stack([np.cos(a), np.sin(a)], axis=1)
    assert not grasp_quality(p, p, [0.0, 0.0], 0.9 * math.tan(beta)).force_closure
    assert grasp_quality(p, p, [0.0, 0.0], 1.1 * math.tan(beta)).force_closure


@pytest.mark.parametrize("n", [2, 3, 4, 6, 12])
def test_frictionless_sphere_never_closure(n):
    """All normals of a sphere pass through its centre: no torque can be resisted."""
    rng = np.random.default_rng(n)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    q = grasp_quality(0.02 * p, p, [0.0, 0.0, 0.0], 0.0)
    assert not q.force_closure and q.epsilon == 0.0 and q.rank <= 3


def test_at_most_six_frictionless_contacts_never_closure():
    """Positively spanning R⁶ needs at least 7 vectors (frictionless contacts: 1 wrench each)."""
    rng = np.random.default_rng(0)
    for _ in range(20):
        p = rng.uniform(-1.0, 1.0, size=(6, 3))
        n = rng.normal(size=(6, 3))
        assert not grasp_quality(p, n, [0.0, 0.0, 0.0], 0.0).force_closure


def test_seven_frictionless_contacts_on_a_cube_close():
    """Seven frictionless contacts on the cube [−1, 1]³ (one per face, a second on −y) are in
    force closure (7 is the minimum in 3-D); removing any one of them breaks closure."""
    p = np.array(
        [
            [1.0, -0.5, -0.5],
            [-1.0, -0.5, 0.5],
            [-0.5, 1.0, 0.0],
            [-1.0, -1.0, 0.5],
            [-1.0, -0.5, 1.0],
            [0.0, 0.5, -1.0],
            [0.5, -1.0, 0.5],
        ]
    )
    n = np.array(
        [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1], [0, -1, 0]], dtype=float
    )
    q = grasp_quality(p, n, [0.0, 0.0, 0.0], 0.0)
    assert q.force_closure and q.rank == 6 and q.edges == 1 and q.epsilon > 0.01
    for k in range(7):
        keep = np.arange(7) != k
        assert not grasp_quality(p[keep], n[keep], [0.0, 0.0, 0.0], 0.0).force_closure


def test_antipodal_hard_contacts_in_3d_are_not_closure():
    """Two hard-finger contacts cannot resist a torque about the line joining them (rank 5),
    whatever the friction — the 3-D counterpart of the planar antipodal grasp."""
    p = np.array([[0.03, 0.0, 0.0], [-0.03, 0.0, 0.0]])
    for mu in (0.0, 0.5, 5.0):
        q = grasp_quality(p, p, [0.0, 0.0, 0.0], mu)
        assert not q.force_closure and q.epsilon == 0.0
        assert q.rank == (1 if mu == 0.0 else 5)


@pytest.mark.parametrize("mu", [0.05, 0.3, 1.0])
def test_three_equator_contacts_close_for_any_friction(mu):
    """Three contacts 120° apart on a sphere's equator: their normals sum to zero (an internal
    squeeze strictly inside the cones) and the grasp map has rank 6 — closure for μ > 0 only."""
    p = equator(3, 0.03)
    assert grasp_quality(p, p, [0.0, 0.0, 0.0], mu).force_closure
    assert not grasp_quality(p, p, [0.0, 0.0, 0.0], 0.0).force_closure


def test_four_contacts_on_a_sphere_with_friction():
    """A regular tetrahedron of contacts on a sphere: closure for μ > 0, not at μ = 0."""
    p = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float) / math.sqrt(3.0)
    assert grasp_quality(0.05 * p, p, [0.0, 0.0, 0.0], 0.2).force_closure
    assert not grasp_quality(0.05 * p, p, [0.0, 0.0, 0.0], 0.0).force_closure


# --- properties ---------------------------------------------------------------------------
def test_epsilon_monotone_in_friction():
    p = equator(3, 0.03)
    eps = [grasp_quality(p, p, [0.0, 0.0, 0.0], mu).epsilon for mu in np.linspace(0.0, 2.0, 21)]
    assert eps[0] == 0.0 and all(b > a for a, b in itertools.pairwise(eps))


def test_epsilon_invariant_to_translation():
    rng = np.random.default_rng(7)
    p = equator(3, 0.03, phase=0.3) + rng.normal(scale=0.002, size=(3, 3))
    n = p / np.linalg.norm(p, axis=1, keepdims=True)
    base = grasp_quality(p, n, [0.0, 0.0, 0.0], 0.5, torque_scale=0.03)
    for shift in rng.normal(scale=0.5, size=(5, 3)):
        moved = grasp_quality(p + shift, n, shift, 0.5, torque_scale=0.03)
        assert moved.epsilon == pytest.approx(base.epsilon, rel=1e-9, abs=1e-12)
        assert moved.force_closure == base.force_closure


def test_epsilon_nearly_invariant_to_rotation():
    """Rotating the grasp rotates the wrenches orthogonally; only the cones' edge phase about
    each normal changes, so ε agrees to the linearisation's resolution."""
    rng = np.random.default_rng(3)
    p = equator(3, 0.03)
    base = grasp_quality(p, p, [0.0, 0.0, 0.0], 0.5, edges=16).epsilon
    for _ in range(3):
        rot = random_rotation(rng)
        eps = grasp_quality(p @ rot.T, p @ rot.T, [0.0, 0.0, 0.0], 0.5, edges=16).epsilon
        assert eps == pytest.approx(base, rel=0.02)


def test_epsilon_matches_support_function_minimum():
    """ε = min over unit directions u of max_i u·w_i (support function of the hull)."""
    p = equator(3, 0.03, phase=0.1)
    w, _, _ = primitive_wrenches(p, p, [0.0, 0.0, 0.0], 0.5, 8)
    eps, rank = epsilon_of_wrenches(w)
    assert rank == 6 and eps > 0.0
    rng = np.random.default_rng(11)
    u = rng.normal(size=(20000, 6))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    support = np.max(u @ w.T, axis=1)
    assert np.all(support >= eps - 1e-12)
    assert support.min() < 1.5 * eps  # sampling approaches the minimum from above


def test_epsilon_of_the_joggled_hull_matches_the_merged_facet_hull():
    # epsilon_of_wrenches asks qhull for a joggled, triangulated hull (QJ, the faster one in
    # 6-D): its ε is the default merged-facet hull's within 1e-9 on random grasps
    rng = np.random.default_rng(5)
    closed = 0
    for _ in range(40):
        k = int(rng.integers(3, 5))
        n = rng.normal(size=(k, 3))
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        w, _, _ = primitive_wrenches(0.03 * n, n, [0.0, 0.0, 0.0], 0.5, 8, 0.03, 0.005)
        eps, rank = epsilon_of_wrenches(w)
        if rank < 6:
            continue
        plain = float(np.min(-ConvexHull(w).equations[:, -1]))
        assert eps == pytest.approx(max(plain, 0.0), abs=1e-9)
        closed += eps > 0.0
    assert closed >= 10  # force-closed grasps among them, not only zeros


def test_more_cone_edges_converge():
    p = equator(3, 0.03)
    eps = [grasp_quality(p, p, [0.0, 0.0, 0.0], 0.5, edges=m).epsilon for m in (8, 16, 32)]
    assert abs(eps[2] - eps[1]) < abs(eps[1] - eps[0]) + 1e-12
    assert eps[2] == pytest.approx(eps[1], rel=0.02)


def test_torque_scale_default_is_largest_contact_radius():
    p = equator(3, 0.04)
    q = grasp_quality(p, p, [0.0, 0.0, 0.0], 0.5)
    assert q.to_dict()["torque_scale"] == q.torque_scale
    assert q.torque_scale == pytest.approx(0.04)
    assert q.epsilon == pytest.approx(grasp_quality(p, p, [0.0, 0.0, 0.0], 0.5, torque_scale=0.04).epsilon)


# --- degenerate and malformed inputs --------------------------------------------------
@pytest.mark.parametrize(
    ("points", "normals"),
    [
        (np.zeros((0, 3)), np.zeros((0, 3))),  # no contacts
        ([[0.0, 0.0, 1.0]], [[0.0, 0.0, 1.0]]),  # one contact
        ([[0, 0, 1.0], [0, 0, 1.0], [0, 0, 1.0]], [[0, 0, 1.0], [0, 1.0, 1.0], [1.0, 0, 1.0]]),  # coincident
        ([[-1.0, 0, 0], [0, 0, 0], [1.0, 0, 0]], [[0, 0, 1.0], [0, 0, -1.0], [0, 0, 1.0]]),  # collinear
        ([[1.0, 0, 0], [0, 1.0, 0], [-1.0, 0, 0], [0, -1.0, 0]], [[0, 0, 1.0]] * 4),  # coplanar, one side
        (np.zeros((0, 2)), np.zeros((0, 2))),
        ([[1.0, 0.0], [2.0, 0.0]], [[1.0, 0.0], [1.0, 0.0]]),  # planar, same side
    ],
)
@pytest.mark.parametrize("mu", [0.0, 0.5])
def test_degenerate_inputs_do_not_crash(points, normals, mu):
    q = grasp_quality(points, normals, None, mu)
    assert isinstance(q, GraspQuality)
    assert not q.force_closure and q.epsilon == 0.0


def test_collinear_contacts_with_friction_are_not_closure():
    """Contacts on one line (e.g. three fingers in a row across a cylinder): no torque about it."""
    p = np.array([[-0.02, 0.0, 0.0], [0.0, 0.0, 0.0], [0.02, 0.0, 0.0]])
    n = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.0, 0.0, 1.0]])
    q = grasp_quality(p, n, [0.0, 0.0, 0.0], 1.0)
    assert not q.force_closure and q.rank == 5


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"points": [[0.0, 0.0, float("nan")]], "normals": [[0.0, 0.0, 1.0]]}, "points"),
        ({"points": [[0.0, 0.0, 0.0]], "normals": [[0.0, 0.0, 0.0]]}, "normals"),
        ({"points": [[0.0, 0.0, 0.0]], "normals": [[0.0, 1.0]]}, "normals"),
        ({"points": [0.0, 0.0, 0.0], "normals": [0.0, 0.0, 1.0]}, "points"),
        ({"points": [[0.0, 0.0, 0.0]], "normals": [[0.0, 0.0, 1.0]], "mu": -0.1}, "mu"),
        ({"points": [[0.0, 0.0, 0.0]], "normals": [[0.0, 0.0, 1.0]], "mu": float("inf")}, "mu"),
        ({"points": [[0.0, 0.0, 0.0]], "normals": [[0.0, 0.0, 1.0]], "edges": 2}, "edges"),
        ({"points": [[0.0, 0.0, 0.0]], "normals": [[0.0, 0.0, 1.0]], "centre": [0.0, 0.0]}, "centre"),
        ({"points": [[1.0, 0.0, 0.0]], "normals": [[0.0, 0.0, 1.0]], "torque_scale": 0.0}, "torque_scale"),
    ],
)
def test_malformed_inputs_name_the_argument(kwargs, message):
    with pytest.raises(ValueError, match=message):
        grasp_quality(**{"centre": None, "mu": 0.5, **kwargs})


def test_contacts_quality_uses_touching_fingers_only():
    p = equator(3, 0.03)
    contacts = {
        f"finger{i + 1}": {"touching": True, "point": p[i].tolist(), "normal": (p[i] / 0.03).tolist()}
        for i in range(3)
    }
    assert contacts_quality(contacts, [0.0, 0.0, 0.0], 0.03, 0.5).force_closure
    contacts["finger3"]["touching"] = False
    q = contacts_quality(contacts, [0.0, 0.0, 0.0], 0.03, 0.5)
    assert q.contacts == 2 and not q.force_closure
    assert q.to_dict()["friction"] == 0.5


def test_primitive_wrench_torques_are_arm_cross_force():
    """Every primitive wrench's torque is (p − c) × f / L, against numpy's cross product."""
    rng = np.random.default_rng(4)
    p, n = rng.normal(size=(3, 3)) * 0.03, rng.normal(size=(3, 3))
    w, scale, m = primitive_wrenches(p, n, [0.01, 0.0, -0.02], 0.4, edges=6)
    arms = np.repeat(p - np.array([0.01, 0.0, -0.02]), m, axis=0)
    np.testing.assert_allclose(w[:, 3:], np.cross(arms, w[:, :3]) / scale, atol=1e-15)


# --- soft-finger contacts (a contact patch of radius a) -----------------------------------
def test_soft_contact_adds_the_two_torsion_wrenches_of_its_patch():
    """Per contact, the cone's edges and two wrenches of the normal force with torque
    ± γ (−n) about the normal, γ = (2/3) μ a (uniform pressure on a disc of radius a)."""
    p = np.array([[0.03, 0.0, 0.0], [-0.03, 0.0, 0.0]])
    mu, a, L = 0.5, 0.008, 0.03
    w, scale, m = primitive_wrenches(p, p, [0.0, 0.0, 0.0], mu, edges=8, torque_scale=L, patch_radius=a)
    assert m == 10 and w.shape == (20, 6) and scale == L
    gamma = 2.0 / 3.0 * mu * a
    torsion = w.reshape(2, 10, 6)[0, 8:]  # the first contact's two extra wrenches
    assert np.allclose(torsion[:, :3], [[-1.0, 0.0, 0.0]] * 2)
    assert np.allclose(sorted(torsion[:, 3]), [-gamma / L, gamma / L])


def test_antipodal_soft_contacts_close_and_their_torsion_bounds_epsilon():
    """Two antipodal pads (a parallel jaw) are in force closure once a > 0: the torque about
    the line through them is resisted by torsional friction alone, at most γ / L per unit
    normal force, which bounds ε (the hull reaches no farther along that torque axis)."""
    p = np.array([[0.03, 0.0, 0.0], [-0.03, 0.0, 0.0]])
    hard = grasp_quality(p, p, [0.0, 0.0, 0.0], 0.5, torque_scale=0.03)
    assert not hard.force_closure
    previous = 0.0
    for a in (0.002, 0.005, 0.01):
        soft = grasp_quality(p, p, [0.0, 0.0, 0.0], 0.5, torque_scale=0.03, patch_radius=a)
        assert soft.force_closure and soft.rank == 6
        assert 0.0 < soft.epsilon <= 2.0 / 3.0 * 0.5 * a / 0.03 + 1e-12
        assert soft.epsilon > previous
        previous = soft.epsilon
    assert grasp_quality(p, p, [0.0, 0.0, 0.0], 0.0, patch_radius=0.01).force_closure is False


def test_a_negative_patch_is_refused_by_name():
    p = np.array([[0.03, 0.0, 0.0], [-0.03, 0.0, 0.0]])
    with pytest.raises(ValueError) as info:
        primitive_wrenches(p, p, None, 0.5, patch_radius=-0.001)
    assert getattr(info.value, "field", None) == "patch_radius"
