"""Agents over Zenoh: an agent in another process (or language) joins a plan.

A remote agent serves its declaration, its precondition test and its action on three
queryables under the service's versioned prefix, and holds a liveliness token while it lives
(:mod:`~eos_svc.remote_agents.wire`)::

    eos/@v1[/<namespace>]/agent/<name>/describe   -> name, stages, default, reads, writes
    eos/@v1[/<namespace>]/agent/<name>/rate       ctx + the entries it reads -> its sub-rating
    eos/@v1[/<namespace>]/agent/<name>/act        ctx + the entries it reads -> outcome + writes
    eos/@v1[/<namespace>]/agent/<name>/alive      (liveliness token)

- :class:`~eos_svc.remote_agents.server.AgentServer` serves any :class:`~eos_svc.agent.Agent`
  (the example program ``clients/remote_agent.py`` serves a plug-in factory);
- :class:`~eos_svc.remote_agents.proxy.RemoteAgent` is the controller's side: an ``Agent``
  that asks the remote one every cycle within a deadline, rates 0 (skipped, the reason in the
  cycle record) when it is late, gone or answers nonsense, and checks its board writes against
  its declared entries before applying any. Pass it to ``plan(..., agents=[proxy])``.
"""

from eos_svc.remote_agents.proxy import RemoteAgent
from eos_svc.remote_agents.server import AgentServer

__all__ = ["AgentServer", "RemoteAgent"]
