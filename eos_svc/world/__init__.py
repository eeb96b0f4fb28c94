"""The world the grasp agents act in (:class:`~eos_svc.world.world.GraspWorld`), what is derived
once per hand, the world's constants, the search's coverage plan, the guarded motions, admission."""
