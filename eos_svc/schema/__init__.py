"""What a plan is asked and what it answers: the request (:mod:`~eos_svc.schema.request`), the
result (:mod:`~eos_svc.schema.result`) and the blackboard's entries (:mod:`~eos_svc.schema.keys`,
their types in :mod:`~eos_svc.schema.board_entries`). Plain data: no Pinocchio, coal or agents."""
