"""How much the Drake verdict depends on the validation's own constants (slow: ~60 validations).

Every case is planned with today's planner; each is validated with the default constants and
with one constant changed: contact stiffness 10⁴ / 10⁵ N/m, squeeze 0.03 / 0.08 rad, finger kp
2.5 / 10 N·m/rad, a 0.5 ms step. Grasps the end agent calls good must be held under every
variant, and the default sphere grasp with its object 15 mm forward (contacts in front of the
centre) dropped under every variant. ``pytest -m slow -s`` prints the table (H held, D dropped,
then the largest displacement in mm).
"""

from __future__ import annotations

import copy

import pytest

from eos_svc.agents import PlanRequest, plan
from eos_svc.experiments.grasp_suite import fixed_suite
from eos_svc.validation import validate_grasp

VARIANTS: dict[str, dict] = {
    "default": {},
    "k 1e4": {"contact_stiffness": 1e4},
    "k 1e5": {"contact_stiffness": 1e5},
    "squeeze .03": {"squeeze": 0.03},
    "squeeze .08": {"squeeze": 0.08},
    "kp 2.5": {"kp": 2.5},
    "kp 10": {"kp": 10.0},
    "dt 0.5 ms": {"time_step": 5e-4},
}
#: (suite object, seed): chosen as good grasps and as grasps once called not good that Drake
#: held; the planner grasps all six well today (a not-good grasp is only printed, not asserted)
CASES = (
    ("sphere d/h 0.20", 1),
    ("sphere d/h 0.50", 1),
    ("box cube 50 yaw 0", 3),
    ("box cube 50 yaw 0", 1),
    ("cylinder along", 3),
    ("ellipsoid long y", 5),
)


@pytest.mark.slow
def test_verdicts_do_not_hang_on_the_constants():
    objects = {o.label: o.spec for o in fixed_suite()}
    rows = []
    good_seen = 0
    for label, seed in CASES:
        result = plan(PlanRequest(obj=objects[label], seed=seed))
        checks = {name: validate_grasp(result, **kw) for name, kw in VARIANTS.items()}
        rows.append((f"{label} s{seed} {'good' if result.good_grasp else 'not good'}", checks))
        if result.good_grasp:
            good_seen += 1
            dropped = [name for name, c in checks.items() if not c.held]
            assert not dropped, f"{label} seed {seed}: a good grasp dropped with {dropped}"
    assert good_seen >= 2  # the planner still makes good grasps of these objects
    forward = copy.deepcopy(plan(PlanRequest(seed=1)).to_dict())
    forward["ground_truth"]["position"][0] += 0.015
    checks = {name: validate_grasp(forward, **kw) for name, kw in VARIANTS.items()}
    rows.append(("default sphere, object 15 mm forward", checks))
    assert not any(c.held for c in checks.values())
    width = max(len(r[0]) for r in rows)
    print("\n" + " " * width + "".join(f"{name:>13}" for name in VARIANTS))
    for name, checks in rows:
        cells = [
            f"{'H' if c.held else 'D'} {max(c.displacement_m.values()) * 1000:7.1f}" for c in checks.values()
        ]
        print(f"{name:<{width}}" + "".join(f"{cell:>13}" for cell in cells))
