#!/usr/bin/python3
"""Driver of python_package_test (tests/python/CMakeLists.txt).

1. python3 -m venv --system-site-packages <tmp>/venv
2. <tmp>/venv/bin/pip install --no-build-isolation --no-deps ./client/python
   (offline: --no-index; nothing is written to the source tree or $HOME)
3. tactforce-server --listen 127.0.0.1:0; the bound port from its stdout line
4. <tmp>/venv/bin/python package_test.py (unittest) with TACTFORCE_TEST_*
   naming the server, the checkout and the venv
The server is stopped (SIGTERM, then SIGKILL) and the temporary directory
removed whatever happens. Exit status: that of the unittest run, or 1.
"""

import argparse
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent


def run(command, **kwargs):
    print("+ " + " ".join(str(c) for c in command), flush=True)
    return subprocess.run([str(c) for c in command], check=True, **kwargs)


def clean_env():
    """The environment without PYTHONPATH / PYTHONHOME / virtualenv hints:
    the venv's tactforce, not a build tree's, is under test."""
    env = dict(os.environ)
    for name in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "PIP_REQUIRE_VIRTUALENV"):
        env.pop(name, None)
    env["PIP_NO_INPUT"] = "1"
    return env


def install(source_dir, tmp):
    venv = tmp / "venv"
    run([sys.executable, "-m", "venv", "--system-site-packages", venv], env=clean_env())
    run([venv / "bin" / "pip", "install", "--no-build-isolation", "--no-deps", "--no-index",
         "--no-cache-dir", "--disable-pip-version-check", "--quiet", source_dir / "client" / "python"],
        env=clean_env(), cwd=tmp)
    return venv


def start_server(bin_dir, tmp):
    """tactforce-server on 127.0.0.1:0: (process, "127.0.0.1:PORT")."""
    server = bin_dir / "tactforce-server"
    if not os.access(server, os.X_OK):
        sys.exit(f"error: {server} not built (target tactforce-server)")
    log = open(tmp / "server.log", "wb")
    process = subprocess.Popen([server, "--listen", "127.0.0.1:0"],
                               stdout=subprocess.PIPE, stderr=log, text=True)
    line = process.stdout.readline()
    match = re.search(r"listening on (\S+:\d+)", line)
    if not match:
        process.kill()
        process.wait()
        log.close()
        sys.exit(f"error: tactforce-server did not start: {line!r}\n"
                 + (tmp / "server.log").read_text(errors="replace"))
    return process, match.group(1)


def stop_server(process):
    if process.poll() is None:
        process.send_signal(signal.SIGTERM)
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source-dir", type=Path, required=True)
    parser.add_argument("--bin-dir", type=Path, required=True)
    args = parser.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="tactforce_py_package."))
    server = None
    try:
        try:
            venv = install(args.source_dir.resolve(), tmp)
        except subprocess.CalledProcessError as error:
            print(f"error: {error} (needs Debian's python3-venv, python3-pip, python3-setuptools, "
                  "python3-wheel, protobuf-compiler, protobuf-compiler-grpc: scripts/setup.sh)",
                  file=sys.stderr)
            return 1
        server, address = start_server(args.bin_dir.resolve(), tmp)
        env = clean_env()
        env.update(TACTFORCE_TEST_SERVER=address, TACTFORCE_TEST_SOURCE_DIR=str(args.source_dir.resolve()),
                   TACTFORCE_TEST_VENV=str(venv), TACTFORCE_TEST_TMP=str(tmp))
        result = subprocess.run([venv / "bin" / "python", HERE / "package_test.py", "-v"], env=env, cwd=tmp)
        if result.returncode != 0 and (tmp / "server.log").exists():
            print("--- tactforce-server stderr ---\n" + (tmp / "server.log").read_text(errors="replace"),
                  file=sys.stderr)
        return result.returncode
    finally:
        if server is not None:
            stop_server(server)
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
