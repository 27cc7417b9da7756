"""What the command-line tools (tactforce.plan, tactforce.inertia) share:
command-line spellings of proto enums, a failed call as one error line and
the CLI's exit code for it, a response as JSON."""

from __future__ import annotations

import sys
from typing import Dict

from google.protobuf import json_format
from google.protobuf.message import Message

from tactforce.errors import TactforceError


def wire_choices(enum: object, prefix: str) -> Dict[str, int]:
    """{'cross-check': SOLVER_CROSS_CHECK, ...}: the values of a generated
    proto enum by their command-line spelling (the wire name without
    `prefix`, lower case, '-' for '_'); the *_UNSPECIFIED value is left out."""
    return {name.removeprefix(prefix).lower().replace("_", "-"): number
            for name, number in enum.items() if not name.endswith("_UNSPECIFIED")}


def report(error: TactforceError, hint: str = "") -> int:
    """Prints 'error: CODE: details<hint>' on stderr; returns the exit code
    `tactforce` uses for that code (2 INVALID_ARGUMENT, 3 UNAVAILABLE,
    4 DEADLINE_EXCEEDED, else 1)."""
    details = error.details.replace("\n", " ").replace("\r", " ")
    print(f"error: {error.code.name}: {details}{hint}", file=sys.stderr)
    return error.exit_code


def print_json(message: Message) -> None:
    """`message` as JSON with the proto field names and every default value."""
    print(json_format.MessageToJson(message, preserving_proto_field_name=True,
                                    including_default_value_fields=True))
