#!/usr/bin/env python3
"""Runs every shell command block of README.md, as a new user would paste it,
and checks that every block marked `<!-- readme-test: file: PATH -->` (the
line before its fence) is exactly the shipped file PATH.

Each ```sh block is run with bash (set -euo pipefail) from the repository
root, except blocks preceded by a line `<!-- readme-test: skip: REASON -->`
(set-up scripts, installs into system folders, servers that run until
stopped: other tests cover them). Before running, the text is adapted to
the test machine, and only in these ways:
  * `build/bin` becomes the binary folder under test (--bin-dir);
  * `127.0.0.1:50051` / `localhost:50051` become a tactforce-server this
    script starts on an ephemeral loopback port;
  * `/tmp/` becomes a private temporary folder.
A block fails when any command exits non-zero; the test fails when any block
fails, printing the block, its output and the exit code.

  run_readme_commands.py --readme README.md --bin-dir build/bin --source-dir .
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

SKIP = re.compile(r"<!--\s*readme-test:\s*skip:\s*(.+?)\s*-->")
FILE = re.compile(r"<!--\s*readme-test:\s*file:\s*(\S+)\s*-->")
FENCE = re.compile(r"^```(\w*)\s*$")


def shell_blocks(text):
    """[(line number, code, skip reason or None)] of the sh/bash blocks."""
    blocks, lines = [], text.splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        lang, start = m.group(1), i
        j = i + 1
        while j < len(lines) and not lines[j].startswith("```"):
            j += 1
        if lang in ("sh", "bash", "shell"):
            skip = None
            for k in range(start - 1, max(start - 3, -1), -1):
                s = SKIP.search(lines[k])
                if s:
                    skip = s.group(1)
                    break
            blocks.append((start + 1, "\n".join(lines[start + 1:j]), skip))
        i = j + 1
    return blocks


def file_blocks(text):
    """[(line number, shipped path, block text)] of the blocks marked as files."""
    lines, out = text.splitlines(), []
    for i in range(1, len(lines)):
        m = FILE.search(lines[i - 1])
        if m and FENCE.match(lines[i]):
            j = i + 1
            while j < len(lines) and not lines[j].startswith("```"):
                j += 1
            out.append((i + 1, m.group(1), "\n".join(lines[i + 1:j]) + "\n"))
    return out


def check_file_blocks(text, source_dir):
    """Number of marked blocks that differ from their file (each printed)."""
    failures = 0
    for line, path, block in file_blocks(text):
        try:
            shipped = open(os.path.join(source_dir, path)).read()
        except OSError as e:
            shipped = f"<cannot read: {e}>"
        if shipped != block:
            failures += 1
            print(f"README.md:{line}: the block differs from the shipped {path}")
        else:
            print(f"README.md:{line}: the block is the shipped {path}")
    return failures


def start_server(bin_dir):
    """A tactforce-server on an ephemeral loopback port and its address (the
    server prints "tactforce-server listening on ADDR" on stdout)."""
    server = subprocess.Popen(
        [os.path.join(bin_dir, "tactforce-server"), "--listen", "127.0.0.1:0", "--log-level", "warn"],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    line = server.stdout.readline()
    prefix = "tactforce-server listening on "
    if not line.startswith(prefix):
        server.kill()
        sys.exit(f"tactforce-server did not start: {line!r}")
    return server, line[len(prefix):].strip()


def adapt(code, bin_dir, address, tmp):
    # /tmp/ first: the binary folder (and the private folder) may be under /tmp.
    code = code.replace("/tmp/", tmp + "/")
    code = re.sub(r"(127\.0\.0\.1|localhost):50051", address, code)
    return code.replace("build/bin", bin_dir)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--readme", required=True)
    parser.add_argument("--bin-dir", required=True)
    parser.add_argument("--source-dir", required=True)
    parser.add_argument("--list", action="store_true", help="only list the blocks")
    args = parser.parse_args()
    text = open(args.readme).read()
    blocks = shell_blocks(text)
    if args.list:
        for line, code, skip in blocks:
            print(f"README.md:{line}: {'skip: ' + skip if skip else 'run'}: {code.splitlines()[0]}")
        return 0
    file_failures = check_file_blocks(text, args.source_dir)
    work = tempfile.mkdtemp(prefix="tactforce_readme_")
    server, address = start_server(os.path.abspath(args.bin_dir))
    failures, ran = 0, 0
    try:
        for line, code, skip in blocks:
            if skip:
                print(f"README.md:{line}: skipped ({skip})")
                continue
            script = "set -euo pipefail\n" + adapt(code, os.path.abspath(args.bin_dir), address, work)
            began = time.time()
            run = subprocess.run(["bash", "-c", script], cwd=args.source_dir, capture_output=True, text=True,
                                 timeout=900)
            ran += 1
            status = "ok" if run.returncode == 0 else f"FAILED (exit {run.returncode})"
            print(f"README.md:{line}: {status} in {time.time() - began:.1f} s")
            if run.returncode != 0:
                failures += 1
                print("---- block ----\n" + script + "\n---- stdout (tail) ----\n" + run.stdout[-3000:] +
                      "\n---- stderr (tail) ----\n" + run.stderr[-3000:])
    finally:
        server.terminate()
        server.wait(timeout=30)
        shutil.rmtree(work, ignore_errors=True)
    print(f"{ran} blocks run, {failures} failed; {file_failures} shipped-file blocks differ")
    return 1 if failures or file_failures or ran == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
