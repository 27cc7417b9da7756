#!/usr/bin/env python3
"""Structure checks run by ctest (tests/CMakeLists.txt: structure_check).

1. Layers: every `#include "tactforce/<lib>/..."` in a library folder must
   name a library that folder may use (ALLOWED below). A folder never includes
   a folder above it, nor a sibling it is not listed with.
2. Function length: no function in library code is longer than MAX_LINES
   (signature line to closing brace).
3. Inside client/: client/ (the shared library) includes neither load/ nor
   commands/, load/ does not include commands/; only main.cc includes the
   command table.
4. Formatting: every tracked .h/.cc is clang-format clean with the repo's
   .clang-format (`clang-format --dry-run --Werror`).
5. Test layout: each tests/<folder>/*_test.cc sits in the folder of the code
   it tests (TEST_FOLDERS; the rule is in tests/README.md).

Usage: check_structure.py [--root DIR] [--longest N]
Prints every violation as path:line: message and exits 1 if there is one;
prints the N longest functions either way.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys

# Folder (relative to the root) -> the tactforce include prefix it provides.
# Order is the layer order, lowest first.
FOLDERS = [
    ("io", "io"),
    ("planner", "planner"),
    ("estimator/inertia", "inertia"),  # before estimator: longest prefix wins
    ("estimator", "estimator"),
    ("sim", "sim"),
    ("audit", "audit"),
    ("experiment", "experiment"),
    ("proto", "v1"),  # generated: tactforce/v1/*.pb.h
    ("api", "api"),
    ("server", "server"),
    ("client", "client"),
    ("examples", "examples"),  # out-of-tree consumers of the installed package
]

# What each folder may include (besides itself).
ALLOWED = {
    "io": set(),
    "planner": {"io"},
    "estimator": {"io", "planner"},
    "inertia": {"io", "planner", "estimator"},
    "sim": {"io"},
    "audit": {"io", "planner", "estimator", "sim"},
    "experiment": {"io", "planner", "estimator", "inertia", "sim"},
    "v1": set(),
    "api": {"io", "planner", "estimator", "inertia", "sim", "audit", "experiment", "v1"},
    "server": {"io", "api", "v1"},
    "client": {"io", "planner", "estimator", "inertia", "sim", "audit", "experiment", "v1", "api"},
    # Only what `cmake --install` exports (cmake/TactforceInstall.cmake).
    "examples": {"io", "planner", "estimator", "inertia", "sim", "audit", "v1", "api"},
}

# Inside client/: its libraries point down too. A file in a folder may
# include (as "sub/header.h") only the client subfolders listed for it;
# main.cc walks the command table and may include commands/.
CLIENT_SUBFOLDERS = ["client/load", "client/commands"]
CLIENT_ALLOWED = {
    "client": set(),
    "client/load": set(),
    "client/commands": {"client/load"},
}
CLIENT_MAIN = "client/main.cc"
CLIENT_INCLUDE_RE = re.compile(r'^\s*#\s*include\s*"(load|commands)/')

# Every folder of C++ code: no function (mains, tests and benchmarks included)
# may be long.
LENGTH_CHECKED = ["io", "planner", "estimator", "sim", "audit", "experiment", "api", "server", "client",
                  "examples", "tests", "bench"]
MAX_LINES = 80

INCLUDE_RE = re.compile(r'^\s*#\s*include\s*"tactforce/([a-z0-9_]+)/')
SOURCE_EXT = (".h", ".cc", ".hpp", ".cpp")


def sources(root, folder):
    base = os.path.join(root, folder)
    for dirpath, dirnames, filenames in os.walk(base):
        dirnames.sort()
        for name in sorted(filenames):
            if name.endswith(SOURCE_EXT):
                yield os.path.join(dirpath, name)


def owner(root, path):
    rel = os.path.relpath(path, root)
    for folder, lib in FOLDERS:
        if rel == folder or rel.startswith(folder + "/"):
            return lib
    return None


def check_layers(root):
    errors = []
    for folder, _ in FOLDERS:
        for path in sources(root, folder):
            lib = owner(root, path)
            with open(path, encoding="utf-8", errors="replace") as f:
                for lineno, line in enumerate(f, 1):
                    m = INCLUDE_RE.match(line)
                    if not m or m.group(1) == lib:
                        continue
                    used = m.group(1)
                    if used not in ALLOWED.get(lib, set()):
                        errors.append("%s:%d: %s/ may not include tactforce/%s/ (allowed: %s)" % (
                            os.path.relpath(path, root), lineno, lib, used,
                            ", ".join(sorted(ALLOWED.get(lib, set()))) or "nothing"))
    return errors


def client_folder(rel):
    for sub in CLIENT_SUBFOLDERS:
        if rel.startswith(sub + "/"):
            return sub
    return "client"


def check_client_layers(root):
    errors = []
    for path in sources(root, "client"):
        rel = os.path.relpath(path, root)
        if rel.startswith("client/python/") or rel == CLIENT_MAIN:
            continue
        folder = client_folder(rel)
        with open(path, encoding="utf-8", errors="replace") as f:
            for lineno, line in enumerate(f, 1):
                m = CLIENT_INCLUDE_RE.match(line)
                if m and "client/" + m.group(1) not in CLIENT_ALLOWED[folder]:
                    errors.append("%s:%d: %s/ may not include client/%s/ (allowed: %s)" % (
                        rel, lineno, folder, m.group(1),
                        ", ".join(sorted(CLIENT_ALLOWED[folder])) or "nothing"))
    return errors


def strip_code(text):
    """Blanks comments, string and character literals (keeps newlines)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = ")" + m.group(1) + '"'
            j = text.find(end, i + m.end())
            j = n if j < 0 else j + len(end)
            out.append('""' + "\n" * text.count("\n", i, j))
            i = j
        elif c == "'" and re.search(r"(?<![\w'])\d[\w']*$", text[max(0, i - 64):i]):
            out.append(c)  # a digit separator (4'000'000), not a character literal
            i += 1
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


FUNCTION_HEADER_RE = re.compile(
    r"\)\s*(const|override|final|noexcept|mutable|&|&&|->\s*[\w:<>,\s*&]+|\s)*$")
NOT_FUNCTION_RE = re.compile(r"^\s*(if|for|while|switch|catch|return)\b|\b(namespace|class|struct|enum|union)\b|=\s*$|\[[^\]]*\]\s*\(")


def functions(path):
    """Yields (name, first line, line count) of each function body in a file."""
    with open(path, encoding="utf-8", errors="replace") as f:
        code = strip_code(f.read())
    stack = []  # (kind, start line, name)
    header_start = 0
    line = 1
    for i, c in enumerate(code):
        if c == "\n":
            line += 1
        elif c == "{":
            header = code[header_start:i]
            body = header.lstrip()
            header_line = line - body.count("\n")
            inside_function = any(kind == "function" for kind, _, _ in stack)
            flat = " ".join(header.split())
            if (not inside_function and FUNCTION_HEADER_RE.search(flat) and
                    not NOT_FUNCTION_RE.search(flat)):
                name = re.findall(r"([~\w:]+)\s*\(", flat)
                name = name[0] if name else "?"
                test = re.search(r"\b(TEST|TEST_F|TEST_P)\s*\(([^)]*)\)", flat)
                if test:  # a gtest case: name it by its suite and name
                    name = "%s(%s)" % (test.group(1), " ".join(test.group(2).split()))
                stack.append(("function", header_line, name))
            else:
                stack.append(("block", line, ""))
            header_start = i + 1
        elif c == "}":
            if stack:
                kind, start, name = stack.pop()
                if kind == "function":
                    yield name, start, line - start + 1
            header_start = i + 1
        elif c == ";":
            header_start = i + 1


def check_lengths(root):
    found = []
    for folder in LENGTH_CHECKED:
        for path in sources(root, folder):
            for name, start, count in functions(path):
                found.append((count, os.path.relpath(path, root), start, name))
    found.sort(reverse=True)
    errors = ["%s:%d: %s is %d lines (limit %d)" % (p, s, n, c, MAX_LINES)
              for c, p, s, n in found if c > MAX_LINES]
    return errors, found


FORMATTED_EXT = (".h", ".cc")
# Never formatted: build trees and generated code.
FORMAT_SKIPPED_DIRS = {".git", "build", "third_party"}


def tracked_sources(root):
    """The repository's .h/.cc files: git's list when root is a checkout, else a walk."""
    try:
        out = subprocess.run(["git", "-C", root, "ls-files", "-z", "--", "*.h", "*.cc"],
                             check=True, capture_output=True).stdout.decode()
        files = [f for f in out.split("\0") if f]
        if files:
            return sorted(files)
    except (OSError, subprocess.CalledProcessError):
        pass
    files = []
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames
                             if d not in FORMAT_SKIPPED_DIRS and not d.startswith("build"))
        files += [os.path.relpath(os.path.join(dirpath, n), root) for n in sorted(filenames)
                  if n.endswith(FORMATTED_EXT)]
    return files


def check_format(root):
    """Every tracked .h/.cc must be unchanged by clang-format (the repo's .clang-format)."""
    exe = shutil.which("clang-format")
    if not exe:
        return ["clang-format not found: install the Debian package clang-format "
                "(scripts/setup.sh does)"]
    files = [f for f in tracked_sources(root) if os.path.isfile(os.path.join(root, f))]
    unformatted = set()
    for i in range(0, len(files), 100):
        batch = files[i:i + 100]
        run = subprocess.run([exe, "--dry-run", "--Werror", "--style=file"] + batch, cwd=root,
                             capture_output=True, text=True)
        for line in run.stderr.splitlines():
            m = re.match(r"^(.+?):\d+:\d+: (error|warning):", line)
            if m:
                unformatted.add(os.path.relpath(os.path.join(root, m.group(1)), root))
        if run.returncode != 0 and not unformatted.intersection(batch):
            return ["clang-format failed (exit %d): %s" % (run.returncode, run.stderr.strip()[:500])]
    return ["%s: not clang-format clean (run clang-format -i %s)" % (f, f)
            for f in sorted(unformatted)]


# tests/<folder> -> the code it tests: a library's include prefix, or the
# binary's folder. tests/inertia tests estimator/inertia (tactforce/inertia/),
# tests/cli tests client/ (the `tactforce` CLI).
TEST_FOLDERS = {
    "io": "io", "planner": "planner", "estimator": "estimator", "inertia": "inertia",
    "sim": "sim", "audit": "audit", "experiment": "experiment", "api": "api",
    "server": "server", "cli": "client",
}
# A test that drives a binary through its harness tests that binary's folder.
BINARY_HARNESSES = [
    ("support/cli_fixture.h", "client"),  # the `tactforce` CLI
    ("server/test_support.h", "server"),  # tactforce-server
    ("server/server_process.h", "server"),
]
NAMESPACE_RE = re.compile(r"^\s*namespace\s+tactforce::(\w+)")
QUOTED_INCLUDE_RE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')


# Where a test's quoted includes are looked up, after its own folder and
# tests/: the root and the folders that export headers without the tactforce/
# prefix (a library's internal src/, client/).
INCLUDE_ROOTS = ["", "client", "audit/src", "planner/src", "estimator/src",
                 "estimator/inertia/src", "sim/src", "experiment/src", "api/src", "server/src"]


def resolve_test_include(root, test_dir, header):
    """Path (relative to root) of a quoted include of a test, or None if not found."""
    bases = [test_dir, os.path.join(root, "tests")] + [os.path.join(root, d) for d in INCLUDE_ROOTS]
    for base in bases:
        path = os.path.join(base, header)
        if os.path.isfile(path):
            return os.path.relpath(path, root)
    return None


def libraries_used(root, rel, seen=None):
    """Library names (include prefixes) a test file uses, with the binaries it drives."""
    seen = seen if seen is not None else set()
    if rel in seen:
        return set()
    seen.add(rel)
    used = set()
    path = os.path.join(root, rel)
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            m = INCLUDE_RE.match(line)
            if m:
                used.add(m.group(1))
                continue
            m = QUOTED_INCLUDE_RE.match(line)
            found = m and resolve_test_include(root, os.path.dirname(path), m.group(1))
            if not found:
                continue
            used |= {folder for harness, folder in BINARY_HARNESSES if found == "tests/" + harness}
            if found.startswith("client/"):
                used.add("client")
            elif not found.startswith("tests/"):
                used.add(owner(root, os.path.join(root, found)))
            elif not found.startswith("tests/support/"):  # a folder's own helper header
                used |= libraries_used(root, found, seen)
    return used


def test_subject(root, rel):
    """The code a test file tests (TEST_FOLDERS' values) and why."""
    used = libraries_used(root, rel)
    with open(os.path.join(root, rel), encoding="utf-8", errors="replace") as f:
        text = f.read()
    for line in text.splitlines():
        m = NAMESPACE_RE.match(line)
        lib = m and ("client" if m.group(1) == "cli" else m.group(1))
        if lib and lib in used:
            return lib, "its tests are in namespace tactforce::%s" % m.group(1)
    for harness, folder in BINARY_HARNESSES:
        if folder in used:
            return folder, "it drives %s through %s" % (
                "the tactforce CLI" if folder == "client" else "tactforce-server", harness)
    m = re.search(r'^\s*#\s*include\s*"tactforce/(\w+)/', text, re.M)
    if m:
        return m.group(1), "its first tactforce include is tactforce/%s/" % m.group(1)
    return None, "it uses no tactforce library"


def check_test_layout(root):
    """Each tests/<folder>/..._test.cc sits in the folder of the code it tests."""
    errors = []
    where = {subject: folder for folder, subject in TEST_FOLDERS.items()}
    for folder in sorted(TEST_FOLDERS):
        for path in sources(root, os.path.join("tests", folder)):
            if not path.endswith("_test.cc"):
                continue
            rel = os.path.relpath(path, root)
            subject, why = test_subject(root, rel)
            if subject != TEST_FOLDERS[folder]:
                errors.append("%s: tests %s (%s): belongs in %s" % (
                    rel, subject or "nothing", why,
                    "tests/%s/" % where[subject] if subject in where else "a tests/ folder"))
    return errors


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    parser.add_argument("--longest", type=int, default=5)
    args = parser.parse_args()
    root = os.path.abspath(args.root)
    errors = check_layers(root) + check_client_layers(root)
    length_errors, found = check_lengths(root)
    errors += length_errors
    errors += check_test_layout(root)
    errors += check_format(root)
    print("longest functions:")
    for count, path, start, name in found[:args.longest]:
        print("  %4d lines  %s:%d  %s" % (count, path, start, name))
    for e in errors:
        print(e)
    print("structure: %d violation(s)" % len(errors))
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
