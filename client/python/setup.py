"""Build step of the tactforce Python package (see pyproject.toml).

Adds to setuptools' build_py:
  * tactforce/v1/<name>_pb2.py and <name>_pb2_grpc.py for every
    proto/tactforce/v1/*.proto of the checkout (a new .proto is picked up
    without editing this file), made by protoc with grpc_python_plugin;
  * tactforce/health/v1/health_pb2.py and health_pb2_grpc.py, the standard
    grpc.health.v1 protocol from grpc-proto's health.proto, compiled inside
    the tactforce package so that no top-level `grpc` folder shadows the
    real grpc package;
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


def health_proto() -> Path:
    """grpc-proto's grpc/health/v1/health.proto ($GRPC_HEALTH_PROTO, else
    Debian's /usr/share/grpc-proto)."""
    path = Path(os.environ.get("GRPC_HEALTH_PROTO") or "/usr/share/grpc-proto/grpc/health/v1/health.proto")
    if not path.is_file():
        sys.exit(f"tactforce setup.py: {path} not found: install Debian's grpc-proto (scripts/setup.sh) "
                 "or set GRPC_HEALTH_PROTO")
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
        self.health_stubs(command[0], command[1], out)
        (out / "tactforce" / "_version.py").write_text(
            f'"""Generated at build time from {root.name}/CMakeLists.txt."""\n'
            f'__version__ = "{cmake_version(root)}"\n', encoding="utf-8")

    def health_stubs(self, protoc: str, plugin: str, out: Path) -> None:
        """tactforce/health/v1/health_pb2(_grpc).py: health.proto compiled
        from a copy under tactforce/health/v1/, so the modules (and the
        import between them) live in the tactforce package and no top-level
        `grpc` folder shadows the real grpc package."""
        with tempfile.TemporaryDirectory(prefix="tactforce-health-") as tmp:
            copy = Path(tmp) / "tactforce" / "health" / "v1" / "health.proto"
            copy.parent.mkdir(parents=True)
            shutil.copyfile(health_proto(), copy)
            subprocess.run([protoc, plugin, f"--proto_path={tmp}", f"--python_out={out}",
                            f"--grpc_python_out={out}", str(copy)], check=True)

    def get_outputs(self, include_bytecode=1):
        outputs = list(super().get_outputs(include_bytecode))
        out = Path(self.build_lib) / "tactforce"
        outputs.append(str(out / "_version.py"))
        outputs += [str(out / "health" / "v1" / "health_pb2.py"), str(out / "health" / "v1" / "health_pb2_grpc.py")]
        for proto in protos(source_dir()):
            outputs += [str(out / "v1" / f"{proto.stem}_pb2.py"), str(out / "v1" / f"{proto.stem}_pb2_grpc.py")]
        return outputs


def check_interpreter() -> None:
    """A clear message instead of setuptools' "invalid command 'bdist_wheel'"
    when this interpreter cannot build a wheel offline (a python3 other than
    Debian's /usr/bin/python3, e.g. pyenv's or conda's, first on PATH), and a
    warning when it lacks the run-time packages."""
    import importlib.util
    has_bdist_wheel = (importlib.util.find_spec("wheel") is not None
                       or importlib.util.find_spec("setuptools.command.bdist_wheel") is not None)
    if not has_bdist_wheel:
        sys.exit(f"tactforce setup.py: {sys.executable} (Python {sys.version.split()[0]}) has no 'wheel' package, "
                 "so pip cannot build the package: make the venv with Debian's /usr/bin/python3 "
                 "(/usr/bin/python3 -m venv --system-site-packages V; python3-wheel, python3-grpcio and "
                 "python3-protobuf are installed for it by scripts/setup.sh), or install wheel, grpcio and "
                 "protobuf into this interpreter's venv from PyPI first")
    missing = [name for name in ("grpc", "google.protobuf") if importlib.util.find_spec(name.split(".")[0]) is None]
    if missing:
        print(f"tactforce setup.py: warning: {sys.executable} cannot import {', '.join(missing)}: "
              "`import tactforce` will fail until grpcio and protobuf are installed for it "
              "(Debian's /usr/bin/python3 has them: python3-grpcio, python3-protobuf)", file=sys.stderr)


check_interpreter()

# Build outside the source tree: setuptools' build/ and *.egg-info go to a
# temporary directory of this process.
_BUILD = tempfile.mkdtemp(prefix="tactforce-python-build-")
atexit.register(shutil.rmtree, _BUILD, ignore_errors=True)

setup(
    version=cmake_version(source_dir()),
    cmdclass={"build_py": BuildPyWithStubs},
    options={"build": {"build_base": _BUILD}, "egg_info": {"egg_base": _BUILD}},
)
