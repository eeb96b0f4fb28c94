"""end: finishes the run when the grasp is complete or can no longer progress.

The verdict is the world's (:meth:`~eos_svc.drivers.protocol.HandDriver.judge_grip`): success
when all fingertips touch; *good* (paper Fig. 2) when the opposing contact and the middle of
the others are ≥ 150° apart seen from the centre (not asked of a mesh) and the contacts are in
force closure (:mod:`eos_svc.drivers.grip_verdict`, μ from the board's ``friction``).
Opportunistic sub-rating: 1 when every finger is done, else 0; chosen with a finger still open,
it fails the run naming it. On the hull of the touches a grip the fingertips feel is not in
force closure is first let go and planned again (:mod:`eos_svc.agents.regrip`).
"""

from __future__ import annotations

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents.base import GRASP, GraspAgent
from eos_svc.agents.finger import DONE_STATES
from eos_svc.agents.regrip import READS as REGRIP_READS
from eos_svc.agents.regrip import WRITES as REGRIP_WRITES
from eos_svc.agents.regrip import Regrip
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.schema import keys
from eos_svc.schema.request import DEFAULT_FRICTION


class EndAgent(GraspAgent):
    """Judges the grasp and ends the run."""

    reads = frozenset({keys.FINGER_STATE, keys.FRICTION}) | REGRIP_READS
    writes = frozenset({keys.OUTCOME}) | REGRIP_WRITES

    def __init__(self, default: float, world: HandDriver) -> None:
        super().__init__("end", (GRASP,), default, world)
        self.regrip = Regrip(world)

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        states = board.get(keys.FINGER_STATE)
        if states and DONE_STATES.issuperset(states.values()):  # every finger is done
            return 1.0
        return 0.0

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        regripped = self.regrip.attempt(board)  # an approximate postulate's grip felt not to close
        if regripped is not None:
            return ActionResult(Outcome.PROGRESS, regripped)
        verdict = self.world.judge_grip(float(board.get(keys.FRICTION, DEFAULT_FRICTION)))
        board.set(keys.OUTCOME, verdict)
        states = board.get(keys.FINGER_STATE, {})
        if verdict["all_touching"]:
            q = verdict["quality"]
            mesh_rule = verdict.get("centre_rule", "diameter") == "force closure"
            if verdict["good"]:
                judgement = "good"
            elif not (verdict["about_diameter"] or mesh_rule):
                judgement = "not good (not about the diameter)"
            elif not q["force_closure"]:
                judgement = "not good (no force closure)"
            else:
                judgement = "not good (not held in the lift test)"
            angle = verdict["diameter_angle_deg"]
            closure = "force closure" if q["force_closure"] else "no force closure"
            return ActionResult(
                Outcome.FINISHED,
                f"precision grip: all fingertips touch; grasp {judgement} ({angle:.0f}° across the "
                f"centre, {closure} at μ={q['friction']:g}, ε={q['epsilon']:.3f})",
                succeeded=True,
            )
        missing = [f for f, c in verdict["contacts"].items() if not c["touching"]]
        why = ", ".join(f"{f} {states.get(f, 'open')}" for f in missing)
        return ActionResult(
            Outcome.FINISHED, f"grasp failed: no fingertip contact for {why}", succeeded=False
        )
