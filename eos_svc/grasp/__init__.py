"""Grasp maths: grasp synthesis on a postulated primitive and the quality of a grasp.

- :mod:`~eos_svc.grasp.sweeps`: the fingers' closing sweeps (fingertip paths in the palm frame);
- :mod:`~eos_svc.grasp.postulate`: the object grasp synthesis plans on;
- :mod:`~eos_svc.grasp.quality`: force closure and the Ferrari–Canny ε;
- :mod:`~eos_svc.grasp.synthesis`: candidate grasps per primitive, checked and scored
  (Miller, Knoop, Christensen, Allen, ICRA 2003).
"""
