"""The world the grasp agents act in: the simulated hand and object
(:class:`~eos_svc.world.world.GraspWorld`), what is derived once per hand
(:class:`~eos_svc.world.hand_context.HandContext`), the world's constants
(:mod:`~eos_svc.world.parameters`), the search's coverage plan, the guarded motions and the
admission check."""
