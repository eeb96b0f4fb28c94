"""Hand drivers: the only way the grasp agents sense and act (:mod:`eos_svc.drivers.protocol`).

The kinematic world (:mod:`eos_svc.drivers.kinematic`, the default: exact, the object fixed)
and a Drake world (:mod:`eos_svc.drivers.drake_world`: the object a free body on a table under
gravity). The agents import the protocol only; the planner builds a world and hands the agents
its driver.
"""

from eos_svc.drivers.protocol import FingerStep, HandDriver, JointState, TactileReading, Touch, WristMove

__all__ = ["FingerStep", "HandDriver", "JointState", "TactileReading", "Touch", "WristMove"]
