"""Errors of the tactforce client and the exit codes of the `tactforce` CLI.

A failed call raises :class:`TactforceError`; its ``exit_code`` is the one
the C++ CLI exits with for the same gRPC status (client/cli_common.h,
ExitCodeFor), so Python tools and the CLI agree:

====  ==========================================================
0     success
1     any other failure (INTERNAL, RESOURCE_EXHAUSTED, UNKNOWN, ...)
2     bad input: INVALID_ARGUMENT (the message names the field)
3     unavailable: the server cannot be reached (UNAVAILABLE)
4     deadline exceeded: no answer within the timeout
====  ==========================================================
"""

from __future__ import annotations

from typing import Optional

import grpc

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_BAD_INPUT = 2
EXIT_UNAVAILABLE = 3
EXIT_DEADLINE = 4

_EXIT_CODES = {
    grpc.StatusCode.OK: EXIT_OK,
    grpc.StatusCode.INVALID_ARGUMENT: EXIT_BAD_INPUT,
    grpc.StatusCode.UNAVAILABLE: EXIT_UNAVAILABLE,
    grpc.StatusCode.DEADLINE_EXCEEDED: EXIT_DEADLINE,
}


def exit_code_for(code: grpc.StatusCode) -> int:
    """The `tactforce` CLI's exit code for a call that ended with `code`."""
    return _EXIT_CODES.get(code, EXIT_FAILURE)


class TactforceError(Exception):
    """A call that failed: the gRPC status and the CLI's exit code for it.

    Attributes:
        code: the grpc.StatusCode (INVALID_ARGUMENT for a request that could
            not even be built from a dict).
        details: the status message; for INVALID_ARGUMENT the server names
            the field ("contacts[0].normal: zero length").
        exit_code: 0-4, as `tactforce` exits (see :func:`exit_code_for`).
        method: the RPC, e.g. "Plan", or "" when unknown.
    """

    code: grpc.StatusCode
    details: str
    exit_code: int
    method: str

    def __init__(self, code: grpc.StatusCode, details: str, method: str = "") -> None:
        super().__init__(f"{code.name}: {details}" if details else code.name)
        self.code = code
        self.details = details
        self.exit_code = exit_code_for(code)
        self.method = method

    @classmethod
    def from_rpc_error(cls, error: grpc.RpcError, method: str = "") -> "TactforceError":
        """From the grpc.RpcError (a grpc.Call) a stub raised."""
        code: Optional[grpc.StatusCode] = error.code() if callable(getattr(error, "code", None)) else None
        details: Optional[str] = error.details() if callable(getattr(error, "details", None)) else None
        if code is None:  # not a grpc.Call: no status to read
            return cls(grpc.StatusCode.UNKNOWN, str(error), method)
        return cls(code, details or "", method)

    def __repr__(self) -> str:
        return (f"TactforceError(code={self.code.name}, details={self.details!r}, "
                f"exit_code={self.exit_code}, method={self.method!r})")
