"""Where the hand *believes* its fingertips are: joint encoders with noise, links with a
calibration error.

The simulated hand moves exactly (the world's kinematics and coal's distances are the truth);
what it reports of a fingertip's pose is computed, as a real hand's controller does, from its
joint encoders' readings through its nominal kinematic model. Two errors come in between:

* **encoder noise** (σ, rad): every finger joint's reading is off by a Gaussian draw, fresh
  at every reading;
* **link-length calibration error** (σ, m): every finger link's true length differs from the
  model's by a Gaussian draw made once per plan (a hand's calibration is wrong the same way
  all along). The model believes the nominal lengths: a link ``δ`` longer than it believes
  puts every point beyond it ``δ`` farther along the link, which the model does not know —
  so the reported tip is the true one less that shift.

The wrist's pose is taken as known exactly (an arm's calibration is another matter). With
both σ at 0 (the default) a reading is the exact kinematics, bit for bit, and no random number
is drawn. This is the world's sensing only: the kinematics of a hand driver would report the
same (:mod:`eos_svc.world.probe_motion` and EP1 take their tip frames from :meth:`tip_frame`).
SI units: metres, radians.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from eos_svc.kinematics import HandModel, HandState


@dataclass
class JointSensing:
    """The errors between a hand's true fingertip frames and those it reports.

    Attributes:
        hand: the hand model (nominal kinematics).
        encoder_noise: σ of every finger joint's encoder reading (rad).
        link_error: per finger, each link's true length less its nominal one (m), from the
            palm outward (the last: the link that carries the tip); drawn once.
        rng: draws the encoder noise (None when ``encoder_noise`` is 0).
        position_sigma: σ of a reported tip-centre position (m): the link errors' σ over the
            links and the encoder noise times each joint's distance to the tip, at the open
            hand, largest over the fingers (the shape fit's noise model takes it).
    """

    hand: HandModel
    encoder_noise: float = 0.0
    link_error: dict[str, np.ndarray] = field(default_factory=dict)
    rng: np.random.Generator | None = None
    position_sigma: float = 0.0
    _scratch: HandState | None = field(default=None, repr=False)

    @classmethod
    def build(
        cls, hand: HandModel, encoder_noise: float, link_error_std: float, seed: np.random.SeedSequence
    ) -> JointSensing:
        """The sensing of one plan: ``encoder_noise`` σ (rad), link lengths off by draws of σ
        ``link_error_std`` (m), both from ``seed`` (nothing is drawn when both are 0)."""
        if encoder_noise == 0.0 and link_error_std == 0.0:
            return cls(hand)
        rng = np.random.default_rng(seed)
        errors = {
            f: rng.normal(0.0, link_error_std, size=len(hand.finger_q_index(f)))
            if link_error_std > 0.0
            else None
            for f in hand.finger_names
        }
        return cls(
            hand,
            encoder_noise=encoder_noise,
            link_error={f: e for f, e in errors.items() if e is not None},
            rng=rng if encoder_noise > 0.0 else None,
            position_sigma=position_sigma(hand, encoder_noise, link_error_std),
        )

    @property
    def exact(self) -> bool:
        """The readings are the exact kinematics (no encoder noise, no link error)."""
        return self.encoder_noise == 0.0 and not self.link_error

    def tip_frame(self, state: HandState, finger: str) -> pin.SE3:
        """The tip frame of ``finger`` the hand reports at ``state`` (world): the nominal
        kinematics at the encoders' readings of its joints, less the shift of its links'
        length errors (see the module doc). The exact frame when :attr:`exact`."""
        tip_id = self.hand.tip_frame_id(finger)
        if self.exact:
            return pin.SE3(state.data.oMf[tip_id])
        idx = self.hand.finger_q_index(finger)
        q = state.q.copy()
        if self.rng is not None:
            q[idx] = q[idx] + self.rng.normal(0.0, self.encoder_noise, size=len(idx))
        if self._scratch is None:
            self._scratch = self.hand.state(q)
        else:
            self._scratch.update(q)
        reported = pin.SE3(self._scratch.data.oMf[tip_id])
        errors = self.link_error.get(finger)
        if errors is not None:
            # the true links (at the true q): each one's direction, from its joint to the next
            # joint (the last: to the tip); a longer link moves the tip along it, unseen
            points = [state.data.oMi[jid].translation for jid in self._joint_ids(finger)]
            points.append(state.data.oMf[tip_id].translation)
            shift = np.zeros(3)
            for k, error in enumerate(errors.tolist()):
                link = np.asarray(points[k + 1]) - np.asarray(points[k])
                length = float(np.linalg.norm(link))
                if length > 0.0:
                    shift += error * link / length
            reported.translation = reported.translation - shift
        return reported

    def _joint_ids(self, finger: str) -> list[int]:
        """Pinocchio joint ids of ``finger``'s joints, from the palm outward."""
        return joint_ids(self.hand, finger)


def joint_ids(hand: HandModel, finger: str) -> list[int]:
    """Pinocchio joint ids of ``finger``'s joints, from the palm outward."""
    return [hand.model.getJointId(name) for name in hand.description.finger(finger).joints]


def position_sigma(hand: HandModel, encoder_noise: float, link_error_std: float) -> float:
    """σ of a reported tip-centre position (m), largest over the fingers at the open hand:
    √(Σ_links σ_L² + Σ_joints (σ_q · joint-to-tip distance)²)."""
    state = hand.state(hand.neutral())
    worst = 0.0
    for finger in hand.finger_names:
        tip = state.data.oMf[hand.tip_frame_id(finger)].translation
        arms = [float(np.linalg.norm(tip - state.data.oMi[j].translation)) for j in joint_ids(hand, finger)]
        variance = len(arms) * link_error_std**2 + sum((encoder_noise * a) ** 2 for a in arms)
        worst = max(worst, float(np.sqrt(variance)))
    return worst
