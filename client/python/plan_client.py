#!/usr/bin/python3
"""Plan fingertip contact forces on a running tactforce-server.

A thin wrapper of the tactforce package's `tactforce.plan` (the same as
`python3 -m tactforce.plan` or, once pip-installed, `tactforce-plan-py`):

    PYTHONPATH=build/python /usr/bin/python3 client/python/plan_client.py \\
        --server 127.0.0.1:50051 [--request client/examples/sphere_pinch.json] \\
        [--solver ipopt] [--stream] [--json]

The package comes from `pip install ./client/python` or, without
installing, from <build>/python (the CMake target tactforce_python_stubs
puts the package and its generated stubs there). Exit codes are those of
the `tactforce` CLI: 0 answer, 1 failure, 2 bad input, 3 unavailable,
4 deadline exceeded.
"""

import sys

try:
    from tactforce.plan import main
except ImportError as error:  # pragma: no cover - environment problem
    sys.exit(f"error: {error}: install the tactforce package (pip install ./client/python, "
             "see client/README.md) or set PYTHONPATH=<build>/python (target tactforce_python_stubs); "
             "it needs Debian's python3-grpcio and python3-protobuf")

if __name__ == "__main__":
    sys.exit(main())
