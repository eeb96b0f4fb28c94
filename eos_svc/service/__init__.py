"""The EOS planning service on Zenoh: wire protocol, server and Python client (``docs/service.md``)."""

from eos_svc.service.client import EosClient
from eos_svc.service.instances import ServiceUnavailableError
from eos_svc.service.plan_attempt import PlanOutcome
from eos_svc.service.protocol import SCHEMA_VERSION, RequestError, decode_request, encode_request
from eos_svc.service.server import PlanService, ServiceStats
from eos_svc.service.session import free_port, loopback, make_config

__all__ = [
    "SCHEMA_VERSION",
    "EosClient",
    "PlanOutcome",
    "PlanService",
    "RequestError",
    "ServiceStats",
    "ServiceUnavailableError",
    "decode_request",
    "encode_request",
    "free_port",
    "loopback",
    "make_config",
]
