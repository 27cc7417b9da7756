"""What every tactforce Python client needs: gRPC, protobuf's JSON mapping
and the generated stubs, with one clear message when any is missing, and
the shared exit codes (0 answer, 1 RPC failed, 2 bad input)."""

import importlib
import sys

EXIT_OK, EXIT_RPC_FAILED, EXIT_BAD_INPUT = 0, 1, 2


def load(*stub_modules):
    """Returns (grpc, json_format, [tactforce.v1.<name> for each name]);
    exits with a hint when Debian's python3-grpcio / python3-protobuf or
    the generated stubs (PYTHONPATH=<build>/python) are missing."""
    try:
        grpc = importlib.import_module("grpc")
        json_format = importlib.import_module("google.protobuf.json_format")
    except ImportError as error:  # pragma: no cover - environment problem
        sys.exit(f"error: {error}: install python3-grpcio and python3-protobuf "
                 "and run with /usr/bin/python3")
    try:
        stubs = [importlib.import_module(f"tactforce.v1.{name}") for name in stub_modules]
    except ImportError as error:  # pragma: no cover - environment problem
        sys.exit(f"error: {error}: set PYTHONPATH to the generated stubs "
                 "(<build>/python, made by the tactforce_python_stubs target)")
    return grpc, json_format, stubs
