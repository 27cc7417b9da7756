"""What every tactforce Python client needs: gRPC, protobuf's JSON mapping
and the generated stubs, with one clear message when any is missing; the
shared exit codes (0 answer, 1 RPC failed, 2 bad input); command-line
spellings of proto enums; a failed RPC as one error line and its exit code;
a response as JSON."""

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


def wire_choices(enum, prefix):
    """{'cross-check': SOLVER_CROSS_CHECK, ...}: the values of a generated
    proto enum by their command-line spelling (the wire name without
    `prefix`, lower case, '-' for '_'); the *_UNSPECIFIED value is left out."""
    return {name.removeprefix(prefix).lower().replace("_", "-"): number
            for name, number in enum.items() if not name.endswith("_UNSPECIFIED")}


def report_rpc_error(grpc, error, hint=""):
    """Prints 'error: CODE: details<hint>' on stderr; returns EXIT_BAD_INPUT
    for INVALID_ARGUMENT (the server names the field), else EXIT_RPC_FAILED."""
    print(f"error: {error.code().name}: {error.details()}{hint}", file=sys.stderr)
    if error.code() == grpc.StatusCode.INVALID_ARGUMENT:
        return EXIT_BAD_INPUT
    return EXIT_RPC_FAILED


def print_json(json_format, message):
    """`message` as JSON with the proto field names and every default value."""
    print(json_format.MessageToJson(message, preserving_proto_field_name=True,
                                    including_default_value_fields=True))
