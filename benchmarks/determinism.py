"""Same plans, cycle for cycle, before and after a change that should not change behaviour.

    .venv/bin/python benchmarks/determinism.py --baseline main

Runs a fixed set of plans — several seeds of the default scene, every object class at the
default position (two seeds each, one noise-free), other sizes and positions, other weights,
and the Allegro hand — once with this checkout and once with the package as it is at git
revision ``--baseline`` (exported with ``git archive`` into a temporary directory and run in a
subprocess), and compares, plan by plan and cycle by cycle: the stage, the chosen agent, its
outcome and its words (``detail``, which prints the measured numbers: distances, curvatures,
ε), then the result's status and reason. The final hand configuration and ε are compared
bit for bit as well (reported separately). Round-off-size numbers printed in the words (an
exponent of -12 or below, e.g. EP1's no-slip residual ``slip ≤ 3.8e-17 m/s``) change their
digits with the order of floating-point operations: a plan that differs only there is reported
as identical up to round-off. Exit code 0 when every plan is identical (up to round-off digits),
1 when one differs (the first differing cycle of each is printed).

``--dump FILE`` writes this checkout's plans as JSON (what the baseline subprocess does).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
ACROSS = [1.5707963267948966, 0.0, 0.0]  # a cylinder or capsule lying across the approach

#: (label, request JSON, hand name)
CASES: list[tuple[str, dict[str, Any], str]] = [
    *[(f"default seed {s}", {"seed": s}, "hand3x3") for s in (1, 2, 3, 7, 11)],
    ("default seed 5 noise-free", {"seed": 5, "tactile_noise": 0.0}, "hand3x3"),
    ("sphere r20 seed 4", {"seed": 4, "object": {"shape": "sphere", "radius": 0.02}}, "hand3x3"),
    (
        "sphere r40 off-centre seed 6",
        {"seed": 6, "object": {"shape": "sphere", "radius": 0.04, "position": [0.23, -0.03, 0.01]}},
        "hand3x3",
    ),
    *[
        (
            f"ellipsoid seed {s}",
            {"seed": s, "object": {"shape": "ellipsoid", "radii": [0.035, 0.03, 0.025]}},
            "hand3x3",
        )
        for s in (1, 2)
    ],
    *[
        (
            f"cylinder seed {s}",
            {"seed": s, "object": {"shape": "cylinder", "radius": 0.02, "length": 0.08, "rpy": ACROSS}},
            "hand3x3",
        )
        for s in (1, 3)
    ],
    *[
        (
            f"capsule seed {s}",
            {"seed": s, "object": {"shape": "capsule", "radius": 0.028, "length": 0.04, "rpy": ACROSS}},
            "hand3x3",
        )
        for s in (2, 4)
    ],
    *[
        (f"box seed {s}", {"seed": s, "object": {"shape": "box", "size": [0.05, 0.06, 0.04]}}, "hand3x3")
        for s in (1, 5)
    ],
    ("weights 0.3/0.7 seed 2", {"seed": 2, "weights": {"default": 0.3, "opportunistic": 0.7}}, "hand3x3"),
    ("weights 1/0 seed 1", {"seed": 1, "weights": {"default": 1.0, "opportunistic": 0.0}}, "hand3x3"),
    ("weights 0/1 seed 1", {"seed": 1, "weights": {"default": 0.0, "opportunistic": 1.0}}, "hand3x3"),
    *[(f"allegro seed {s}", {"seed": s}, "allegro") for s in (1, 2)],
]


def run_cases() -> list[dict[str, Any]]:
    """Every case planned with the ``eos_svc`` importable now (no deadline: cycle counts must not
    depend on the machine's load)."""
    from eos_svc.agents import PlanRequest, plan

    hands: dict[str, Any] = {"hand3x3": None}
    out = []
    for label, data, hand_name in CASES:
        if hand_name not in hands:
            hands[hand_name] = named_hand(hand_name)
        request = PlanRequest.from_dict({**data, "deadline_s": None})
        result = plan(request, hand=hands[hand_name])
        d = result.to_dict()
        out.append(
            {
                "label": label,
                "cycles": [
                    [r.seq, r.stage, r.chosen, None if r.outcome is None else r.outcome.value, r.detail]
                    for r in result.trace
                ],
                "status": d["status"],
                "reason": d["reason"],
                "bits": {"q_final": _hex(d.get("q_final")), "epsilon": _hex(d.get("epsilon"))},
            }
        )
    return out


def named_hand(name: str) -> Any:
    """The hand ``name`` from its description (``eos_svc.hands``), or, in a baseline older than
    the descriptions, from the function that assembled the Allegro."""
    try:
        from eos_svc.hands import load_hand_named
    except ImportError:  # a baseline before eos_svc.hands
        from eos_svc.kinematics import allegro_hand  # type: ignore[attr-defined]

        return allegro_hand()
    return load_hand_named(name)


def _hex(value: Any) -> Any:
    """Floats as their exact hex form (bit-for-bit comparison through JSON)."""
    if isinstance(value, float):
        return value.hex()
    if isinstance(value, list):
        return [_hex(v) for v in value]
    return value


def baseline_cases(rev: str) -> list[dict[str, Any]]:
    """The same cases run by the package at git revision ``rev`` (in a subprocess)."""
    with tempfile.TemporaryDirectory(prefix="eos_determinism_") as tmp:
        archive = subprocess.run(
            ["git", "-C", str(ROOT), "archive", rev, "eos_svc", "urdf"], capture_output=True, check=True
        ).stdout
        subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
        out = Path(tmp) / "plans.json"
        env = {**os.environ, "PYTHONPATH": tmp}
        subprocess.run(
            [sys.executable, str(Path(__file__).resolve()), "--dump", str(out)], env=env, check=True, cwd=tmp
        )
        loaded = json.loads(out.read_text())
        if not loaded["source"].startswith(tmp):
            raise SystemExit(f"the baseline run imported {loaded['source']}, not the exported revision")
        plans: list[dict[str, Any]] = loaded["plans"]
        return plans


#: a number printed in scientific notation with an exponent of -12 or below: a round-off residual
#: (e.g. EP1's "slip ≤ 3.8e-17 m/s"), whose digits change with the order of floating-point operations
ROUND_OFF = re.compile(r"\d(?:\.\d+)?e-(?:1[2-9]|[2-9]\d|\d{3})")


def without_round_off(cycle: list[Any]) -> list[Any]:
    """A cycle with round-off-size numbers in its words replaced by ``≈0``."""
    return [*cycle[:4], ROUND_OFF.sub("≈0", cycle[4] or "")]


def compare(before: list[dict[str, Any]], after: list[dict[str, Any]], exact: bool = True) -> list[str]:
    """Differences, one text per differing plan (empty when identical); ``exact=False`` ignores
    the digits of round-off-size numbers in the cycles' words."""
    problems = []
    for b, a in zip(before, after, strict=True):
        label = a["label"]
        for cb, ca in zip(b["cycles"], a["cycles"], strict=False):  # lengths compared below
            if not exact:
                cb, ca = without_round_off(cb), without_round_off(ca)
            if cb != ca:
                problems.append(f"{label}: cycle {ca[0]} differs:\n  before {cb}\n  after  {ca}")
                break
        else:
            if len(b["cycles"]) != len(a["cycles"]):
                problems.append(f"{label}: {len(b['cycles'])} cycles before, {len(a['cycles'])} after")
            elif (b["status"], b["reason"]) != (a["status"], a["reason"]):
                before_end, after_end = f"{b['status']}/{b['reason']!r}", f"{a['status']}/{a['reason']!r}"
                problems.append(f"{label}: result {before_end} -> {after_end}")
    return problems


def largest_bit_change(before: list[dict[str, Any]], after: list[dict[str, Any]]) -> float:
    """The largest |difference| between the plans' q_final entries and ε (rad, m or ε units)."""
    largest = 0.0
    for b, a in zip(before, after, strict=True):
        old = [*(b["bits"]["q_final"] or []), b["bits"]["epsilon"]]
        new = [*(a["bits"]["q_final"] or []), a["bits"]["epsilon"]]
        for x, y in zip(old, new, strict=False):
            if isinstance(x, str) and isinstance(y, str):
                largest = max(largest, abs(float.fromhex(x) - float.fromhex(y)))
    return largest


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", default="main", help="git revision to compare with (main)")
    parser.add_argument("--dump", type=Path, help="write this checkout's plans as JSON and stop")
    args = parser.parse_args(argv)
    if args.dump:
        import eos_svc

        args.dump.write_text(json.dumps({"source": eos_svc.__file__, "plans": run_cases()}))
        return 0
    before = baseline_cases(args.baseline)
    import eos_svc

    print(f"this checkout: {Path(eos_svc.__file__).parent}; baseline: {args.baseline}")
    after = run_cases()
    exact = compare(before, after)
    problems = compare(before, after, exact=False)
    bits = [a["label"] for b, a in zip(before, after, strict=True) if b["bits"] != a["bits"]]
    total = sum(len(a["cycles"]) for a in after)
    for p in problems:
        print(p)
    if exact and not problems:
        print(
            f"{len(exact)} plan(s) differ only in the digits of round-off-size numbers (< 1e-11) "
            "in the cycles' words, e.g. the first:\n" + exact[0]
        )
    print(
        f"{len(after)} plans, {total} cycles: "
        + (
            "identical cycle for cycle"
            if not exact
            else "identical cycle for cycle up to round-off digits"
            if not problems
            else f"{len(problems)} plan(s) differ"
        )
        + (
            "; q_final and ε identical bit for bit"
            if not bits
            else f"; q_final/ε bits differ in {len(bits)} plan(s), "
            f"by at most {largest_bit_change(before, after):.1e}"
        )
    )
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
