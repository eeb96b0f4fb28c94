"""Per-step time of EP1's rolling step and the time of one EP1 run, with every backend side by
side and, with ``--baseline REV``, the code of an earlier git revision measured in the same run.

One step = kinematics (Pinocchio), contact (coal), tactile reading, QP, integration.
Run: ``.venv/bin/python benchmarks/bench_rolling.py [--baseline 9a82297] [--steps N]``.

Rows: ``as used`` — the default: the closed-form solve when the bounds are inactive, OSQP (set
up once per thread, updated and warm-started) otherwise; ``advance()`` — the same step as EP1
takes it, ``RollingQP.advance`` (no RollingStep, Contact or TactileReading); ``osqp only`` — ``direct=False``,
every step through OSQP; each other installed qpsolvers backend through
``qpsolvers.solve_problem`` on the same live Problem (``direct=False``); ``solve_qp osqp
(naive)`` — ``qpsolvers.solve_qp(..., solver="osqp")`` every step (OSQP set up from scratch,
default tolerances); ``baseline REV`` — the default of that revision; ``floor`` — the library
calls of one default step alone (Pinocchio FK with the last q̇, joint Jacobians, frame Jacobian and
classical acceleration; coal distance and witness; the sensor's normal draw; the four 3-vectors a
step returns; the two matmuls, ``dgels``, the q update and the q̇ copy), with none of the step's
arithmetic, checks or records: what no Python-level change to the step can go below. Rows are timed
in interleaved rounds (the machine is shared; drift hits every row alike). Then one EP1 run as the
planner calls it (omega 2 rad/s, dt 10 ms, 16 steps per direction, directions 0° and 90°: 64
steps), the breakdown of the default step (its helpers timed one by one), and the verdict on the
60 µs goal on this machine, with a yardstick of the machine's speed (Pinocchio FK + frame
placements, timed in the same rounds).
"""

from __future__ import annotations

import argparse
import functools
import inspect
import statistics
import sys
import time
import timeit
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pinocchio as pin
import qpsolvers
from scipy.linalg import lapack

import eos_svc.kinematics as kin_now
import eos_svc.kinematics.ep1
import eos_svc.kinematics.rolling  # noqa: F401  (kin_now.rolling)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _baseline import load_kinematics

EP1_KW: dict[str, Any] = {"omega": 2.0, "dt": 0.01, "steps_per_direction": 16, "directions": (0.0, 90.0)}
GOAL_US = 60.0  # the project's goal for one EP1 rolling step, median
_LWA = pin.LOCAL_WORLD_ALIGNED


def bare_step(rq: Any) -> None:
    """The library calls of one default step of the current ``RollingQP`` (second order, tactile
    sensor, closed-form solve), with its arrays and nothing else: no arithmetic, no checks, no
    records. The constraint rows and targets are the last real step's (M, b); q still moves by
    the solution, so the configuration (and coal's work) evolves as in a roll."""
    model, data, fid = rq._model, rq._data, rq._fid
    pin.forwardKinematics(model, data, rq._qk, rq._qdk, rq._zero_nv)
    pin.computeJointJacobians(model, data)
    J = pin.getFrameJacobian(model, data, fid, _LWA)
    c = rq._c_view
    probe = rq._probe
    probe.tf_tip.setTranslation(c)
    res = probe.res
    res.clear()
    probe.dist(probe.tf_obj, probe.tf_tip, probe.req, res)
    p = res.getNearestPoint1()
    v = c.tolist()
    p.tolist()
    np.array(v), np.array(v)  # the contact's point and normal
    rq._R_view.tolist()
    rq.tactile.rng.normal(0.0, rq.tactile.noise_std, size=2).tolist()
    np.array(v), np.array(v)  # the reading's point and normal
    np.matmul(rq._M, J if rq._jsel is None else J[:, rq._jsel], out=rq._C)
    pin.getFrameClassicalAcceleration(model, data, fid, _LWA).vector.tolist()
    _, x, _ = lapack.dgels(rq._C, rq._b_ext)
    np.matmul(rq._C, x, out=rq._res6).tolist()
    rq._qa += x * rq.dt
    rq._qdot.copy()


def _naive_solve(rq: Any, kin: ModuleType) -> Callable[[], tuple[np.ndarray, int]]:
    def solve() -> tuple[np.ndarray, int]:
        p = rq.problem
        x = qpsolvers.solve_qp(p.P, p.q, None, None, p.A, p.b, p.lb, p.ub, solver="osqp")
        if x is None:
            raise kin.rolling.RollingQPError("no solution", rq.problem_copy(), "osqp (naive)", "None")
        return x, 0

    return solve


class Stepper:
    """Back-and-forth rolls of finger1 on a 4 cm sphere; ``run(n)`` times ``n`` more steps."""

    def __init__(self, kin: ModuleType, solver: str = "osqp", naive: bool = False, direct: bool | None = None,
                 leg: int = 50, bare: bool = False, lean: bool = False) -> None:
        self.kin, self.solver, self.naive, self.leg, self.bare = kin, solver, naive, leg, bare
        self.lean = lean  # time RollingQP.advance (EP1's step without its records), not step
        params = inspect.signature(kin.rolling.RollingQP).parameters
        self.kw: dict[str, Any] = {} if direct is None or "direct" not in params else {"direct": direct}
        self.sc = kin.ep1.ep1_scene("sphere", 0.04)
        self.st = self.sc.hand.state(kin.ep1.place_hand_for_ep1(self.sc, "finger1"))
        self.F = kin.ep1.contact_frame(self.sc.contact(self.st, "finger1").normal)
        self.sensor = kin.TactileSensor(2e-4, rng=0)
        self.sign = 1.0
        self.k = leg
        self.rq: Any = None
        self.worst = 0.0

    def _new_leg(self) -> None:
        if self.rq is not None:
            self.st.update(self.rq.q)
        self.rq = self.kin.rolling.RollingQP(
            self.st, "finger1", self.F[:, 0], self.sign * 0.5, 0.01, "osqp" if self.naive else self.solver,
            scene=self.sc, tactile=self.sensor, project_axis=False, **self.kw,
        )  # fmt: skip
        if self.naive:
            self.rq._solve_osqp = _naive_solve(self.rq, self.kin)
        self.sign = -self.sign
        self.k = 0
        for _ in range(self.leg // 5):  # not timed: the first steps of a roll (set-up)
            self.worst = max(self.worst, self.rq.step().slip_speed)
            self.k += 1

    def run(self, n: int) -> list[float]:
        times = []
        pc = time.perf_counter
        for _ in range(n):
            if self.k >= self.leg:
                self._new_leg()
            if self.bare:
                step = functools.partial(bare_step, self.rq)
                t0 = pc()
                step()
                times.append(pc() - t0)
                self.k += 1
                continue
            if self.lean:
                advance = self.rq.advance
                t0 = pc()
                slip = advance()[5]
                times.append(pc() - t0)
                self.k += 1
                self.worst = max(self.worst, slip)
                continue
            step = self.rq.step
            t0 = pc()
            s = step()
            times.append(pc() - t0)
            self.k += 1
            self.worst = max(self.worst, s.slip_speed)
        return times


def ep1_runner(kin: ModuleType) -> Callable[[], Any]:
    sc = kin.ep1.ep1_scene("sphere", 0.04)
    q0 = kin.ep1.place_hand_for_ep1(sc, "finger1")
    st = sc.hand.state(q0)
    sensor = kin.TactileSensor(2e-4, rng=0)

    def run() -> Any:
        st.update(q0)
        return kin.ep1.run_ep1(sc, st, "finger1", sensor, **EP1_KW)

    return run


def breakdown(n: int = 2000) -> dict[str, float]:
    """Median µs of each part of the default step (current code)."""
    RollingQP = kin_now.rolling.RollingQP
    sc = kin_now.ep1.ep1_scene("sphere", 0.04)
    st = sc.hand.state(kin_now.ep1.place_hand_for_ep1(sc, "finger1"))
    F = kin_now.ep1.contact_frame(sc.contact(st, "finger1").normal)
    names = ("kinematics", "contact", "tactile", "build", "solve (direct)", "whole step")
    parts: dict[str, list[float]] = {k: [] for k in names}
    pc = time.perf_counter
    rq = RollingQP(st, "finger1", F[:, 0], 0.5, 0.01, scene=sc, tactile=kin_now.TactileSensor(2e-4, rng=0),
                   project_axis=False)  # fmt: skip
    sign = 1.0
    while len(parts["whole step"]) < n:
        rq.retarget(F[:, 0], sign * 0.5, project_axis=False)
        rq.step()
        for _ in range(49):
            t0 = pc()
            rq.kinematics()
            t1 = pc()
            c = rq.contact()
            t2 = pc()
            rq.read_tactile(c)
            t3 = pc()
            rq._build(c)
            t4 = pc()
            rq._solve_direct()
            t5 = pc()
            rq.step()  # advances (its own draw of the sensor noise)
            t6 = pc()
            for k, a, b in zip(names, (t0, t1, t2, t3, t4, t5), (t1, t2, t3, t4, t5, t6), strict=True):
                parts[k].append(b - a)
        sign = -sign
    return {k: 1e6 * statistics.median(v) for k, v in parts.items()}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--steps", type=int, default=2000, help="timed steps per row")
    p.add_argument("--runs", type=int, default=31, help="timed EP1 runs per row")
    p.add_argument("--baseline", default=None, help="git revision to time beside the current code")
    a = p.parse_args(argv)
    base = load_kinematics(a.baseline) if a.baseline else None
    rows: list[tuple[str, Stepper, int]] = [
        ("as used (direct, else osqp)", Stepper(kin_now), a.steps),
        ("advance(): EP1's step, no records", Stepper(kin_now, lean=True), a.steps),
        ("osqp only (direct=False)", Stepper(kin_now, direct=False), a.steps),
        *[
            (f"{s} (solve_problem)", Stepper(kin_now, s, direct=False), a.steps)
            for s in qpsolvers.available_solvers
            if s != "osqp"
        ],
        ("solve_qp osqp (naive)", Stepper(kin_now, naive=True, direct=False), max(200, a.steps // 10)),
        ("floor: the step's library calls", Stepper(kin_now, bare=True), a.steps),
    ]
    if base is not None:
        rows.insert(1, (f"baseline {a.baseline} (as used then)", Stepper(base), a.steps))
    times: dict[str, list[float]] = {name: [] for name, _, _ in rows}
    # a yardstick of the machine's speed: Pinocchio FK + frame placements (hand3x3), timed in
    # the same interleaved rounds (same load as the rows). The former
    # np.cross calibration (55 µs here vs 16 µs) overstated the gap: np.cross is Python-level
    # numpy code whose cost follows numpy's version more than the machine.
    sc = kin_now.ep1.ep1_scene("sphere", 0.04)
    model, data = sc.hand.model, sc.hand.model.createData()
    q = kin_now.ep1.place_hand_for_ep1(sc, "finger1")
    fk_runs: list[float] = []
    rounds = 20
    for _ in range(rounds):  # interleaved
        for name, stepper, n in rows:
            times[name] += stepper.run(max(1, n // rounds))
        fk_reps = timeit.repeat(lambda: pin.framesForwardKinematics(model, data, q), number=200, repeat=5)
        fk_runs += [t / 200 for t in fk_reps]
    med0 = 1e6 * statistics.median(times[rows[0][0]])
    print("EP1 rolling step (kinematics + contact + tactile + QP + integration), sphere R = 4 cm")
    print(f"{'row':<36}{'median µs':>11}{'p90 µs':>10}{'ratio':>8}{'max no-slip residual m/s':>27}")
    for name, stepper, _ in rows:
        ts = times[name]
        med = 1e6 * statistics.median(ts)
        p90 = 1e6 * float(np.percentile(ts, 90))
        worst = "-" if stepper.bare else f"{stepper.worst:.1e}"
        print(f"{name:<36}{med:>11.1f}{p90:>10.1f}{med / med0:>8.2f}{worst:>27}")
    floor = 1e6 * statistics.median(times[rows[-1][0]])

    runners = [("current", ep1_runner(kin_now))]
    if base is not None:
        runners.append((f"baseline {a.baseline}", ep1_runner(base)))
    ep1_ms: dict[str, list[float]] = {name: [] for name, _ in runners}
    for _, f in runners:
        f()  # warm up (thread caches, imports)
    for _ in range(a.runs):
        for name, f in runners:
            t0 = time.perf_counter()
            f()
            ep1_ms[name].append(1e3 * (time.perf_counter() - t0))
    print(f"\nEP1 run as the planner calls it ({EP1_KW}), median of {a.runs} runs:")
    cur = statistics.median(ep1_ms["current"])
    for name, _ in runners:
        med = statistics.median(ep1_ms[name])
        print(f"  {name:<28}{med:8.2f} ms   ratio {med / cur:5.2f}")

    print("\nbreakdown of the default step (median µs; its helpers timed one by one; the step calls them):")
    for k, v in breakdown(min(a.steps, 2000)).items():
        print(f"  {k:<16}{v:8.1f}")

    fk = 1e6 * statistics.median(fk_runs)
    print(f"\ncalibration (same rounds): Pinocchio FK + frame placements {fk:.2f} µs here; "
          f"step = {med0 / fk:.0f} FK, floor = {floor / fk:.0f} FK")  # fmt: skip
    verdict = "MET" if med0 <= GOAL_US else "NOT met"
    print(f"goal (one step ≤ {GOAL_US:.0f} µs median) on THIS machine: {verdict} — {med0:.1f} µs as used; "
          f"the library calls alone take {floor:.1f} µs here")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
