"""tactforce: Python client of the tactforce fingertip-force service.

    import tactforce

    with tactforce.Client("127.0.0.1:50051", timeout=10) as client:
        response = client.Plan(request)   # a PlanRequest or its JSON dict

Contents:
    Client                  one method per RPC of tactforce.v1 (client.py)
    TactforceError          a failed call: .code, .details, .exit_code
    exit_code_for           the `tactforce` CLI's exit code for a gRPC code
    EXIT_OK ... EXIT_DEADLINE   those exit codes (0, 1, 2, 3, 4)
    tls_credentials         TLS credentials from PEM files
    HAS_SERVER_INFO         True if built with tactforce/v1/info.proto
    tactforce.v1            the generated messages and stubs (*_pb2, *_pb2_grpc)
    tactforce.health.v1     grpc.health.v1 messages and stubs (health_pb2, health_pb2_grpc)
    tactforce.friction      slip-trial CSVs -> FrictionRequest (read_trial, friction_request)
    tactforce.audit         measured-data CSV -> AuditRequest (read_samples, audit_request)
    tactforce.plan          `python3 -m tactforce.plan` (tactforce-plan-py)
    tactforce.inertia       `python3 -m tactforce.inertia` (tactforce-inertia-py); read_samples
                            reads the inertia CSV
    __version__             the tactforce version (top-level CMakeLists.txt)
"""

from tactforce._version import __version__
from tactforce.client import HAS_SERVER_INFO, Client, tls_credentials
from tactforce.errors import (EXIT_BAD_INPUT, EXIT_DEADLINE, EXIT_FAILURE, EXIT_OK, EXIT_UNAVAILABLE,
                              TactforceError, exit_code_for)

__all__ = [
    "Client", "TactforceError", "exit_code_for", "tls_credentials", "HAS_SERVER_INFO",
    "EXIT_OK", "EXIT_FAILURE", "EXIT_BAD_INPUT", "EXIT_UNAVAILABLE", "EXIT_DEADLINE",
    "__version__",
]
