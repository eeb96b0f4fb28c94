"""Plug-in agents of the grasp planner: how other algorithms join a plan.

- :mod:`~eos_svc.agents.plugins.loading`: naming plug-ins (the ``eos_svc.agents`` entry-point
  group, ``module:attr``), building them for a plan and checking their contract;
- :mod:`~eos_svc.agents.plugins.sampled_grasp_points`: the worked example, a second grasp-points
  agent with another candidate sampler.

The contract is written out in ``docs/extending.md`` ("A new agent").
"""
