"""Build step of the tactforce Python package (see pyproject.toml).

Adds to setuptools' build_py:
  * tactforce/v1/<name>_pb2.py and <name>_pb2_grpc.py for every
    proto/tactforce/v1/*.proto of the checkout (a new .proto is picked up
    without editing this file), made by protoc with grpc_python_plugin;
  * tactforce/_version.py with the version of the top-level CMakeLists.txt
    (`project(tactforce VERSION x.y.z ...)`), also the package's version.
Both are written into the build directory only, and the whole build (build/,
*.egg-info) happens in a temporary directory that is removed afterwards, so
nothing is left in the source tree.

The checkout is found two levels up (client/python/../..) or at
$TACTFORCE_SOURCE_DIR; protoc and grpc_python_plugin on PATH (Debian's
protobuf-compiler and protobuf-compiler-grpc) or at $PROTOC and
$GRPC_PYTHON_PLUGIN.
"""

import atexit
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent


def source_dir() -> Path:
    root = Path(os.environ.get("TACTFORCE_SOURCE_DIR") or HERE.parent.parent)
    if not (root / "CMakeLists.txt").is_file() or not (root / "proto" / "tactforce" / "v1").is_dir():
        sys.exit(f"tactforce setup.py: {root} is not the tactforce checkout (no CMakeLists.txt and "
                 "proto/tactforce/v1): build from the repository, pip install ./client/python, "
                 "or set TACTFORCE_SOURCE_DIR")
    return root


def cmake_version(root: Path) -> str:
    """x.y.z from `project(tactforce VERSION x.y.z` of the top-level CMakeLists.txt."""
    text = (root / "CMakeLists.txt").read_text(encoding="utf-8")
    match = re.search(r"project\s*\(\s*tactforce\s+VERSION\s+([0-9][0-9A-Za-z.+-]*)", text)
    if not match:
        sys.exit(f"tactforce setup.py: no 'project(tactforce VERSION x.y.z' in {root / 'CMakeLists.txt'}")
    return match.group(1)


def tool(variable: str, name: str, package: str) -> str:
    path = os.environ.get(variable) or shutil.which(name)
    if not path:
        sys.exit(f"tactforce setup.py: {name} not found: install Debian's {package} "
                 f"(scripts/setup.sh) or set {variable}")
    return path


def protos(root: Path) -> list:
    found = sorted((root / "proto" / "tactforce" / "v1").glob("*.proto"))
    if not found:
        sys.exit(f"tactforce setup.py: no .proto in {root / 'proto/tactforce/v1'}")
    return found


class BuildPyWithStubs(build_py):
    """build_py, then the generated stubs and _version.py in build_lib."""

    def run(self):
        super().run()
        root = source_dir()
        proto_dir = root / "proto"
        out = Path(self.build_lib)
        command = [
            tool("PROTOC", "protoc", "protobuf-compiler"),
            f"--plugin=protoc-gen-grpc_python={tool('GRPC_PYTHON_PLUGIN', 'grpc_python_plugin', 'protobuf-compiler-grpc')}",
            f"--proto_path={proto_dir}",
            f"--python_out={out}",
            f"--grpc_python_out={out}",
            *[str(p) for p in protos(root)],
        ]
        self.announce("running " + " ".join(command), level=2)
        subprocess.run(command, check=True)
        (out / "tactforce" / "_version.py").write_text(
            f'"""Generated at build time from {root.name}/CMakeLists.txt."""\n'
            f'__version__ = "{cmake_version(root)}"\n', encoding="utf-8")

    def get_outputs(self, include_bytecode=1):
        outputs = list(super().get_outputs(include_bytecode))
        out = Path(self.build_lib) / "tactforce"
        outputs.append(str(out / "_version.py"))
        for proto in protos(source_dir()):
            outputs += [str(out / "v1" / f"{proto.stem}_pb2.py"), str(out / "v1" / f"{proto.stem}_pb2_grpc.py")]
        return outputs


# Build outside the source tree: setuptools' build/ and *.egg-info go to a
# temporary directory of this process.
_BUILD = tempfile.mkdtemp(prefix="tactforce-python-build-")
atexit.register(shutil.rmtree, _BUILD, ignore_errors=True)

setup(
    version=cmake_version(source_dir()),
    cmdclass={"build_py": BuildPyWithStubs},
    options={"build": {"build_base": _BUILD}, "egg_info": {"egg_base": _BUILD}},
)
