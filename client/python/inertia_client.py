#!/usr/bin/python3
"""Fit mass, centre of mass and inertia on a running tactforce-server.

A thin wrapper of the tactforce package's `tactforce.inertia` (the same as
`python3 -m tactforce.inertia` or, once pip-installed, `tactforce-inertia-py`):

    PYTHONPATH=build/python /usr/bin/python3 client/python/inertia_client.py \\
        --server 127.0.0.1:50051 --csv run.csv [--method factor-graph] \\
        [--truth truth.json] [--mesh Hammer.mesh.json] [--batch 500] [--json]

The package comes from `pip install ./client/python` or, without
installing, from <build>/python (the CMake target tactforce_python_stubs
puts the package and its generated stubs there). Exit codes are those of
the `tactforce` CLI: 0 fitted, 1 failure, 2 bad input, 3 unavailable,
4 deadline exceeded.
"""

import sys

try:
    from tactforce.inertia import main
except ImportError as error:  # pragma: no cover - environment problem
    sys.exit(f"error: {error}: install the tactforce package (pip install ./client/python, "
             "see client/README.md) or set PYTHONPATH=<build>/python (target tactforce_python_stubs); "
             "it needs Debian's python3-grpcio and python3-protobuf")

if __name__ == "__main__":
    sys.exit(main())
