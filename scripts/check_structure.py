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

Usage: check_structure.py [--root DIR] [--longest N]
Prints every violation as path:line: message and exits 1 if there is one;
prints the N longest functions either way.
"""
import argparse
import os
import re
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

# Library code whose functions must stay short.
LENGTH_CHECKED = ["io", "planner", "estimator", "sim", "audit", "experiment", "api", "server", "client",
                  "examples"]
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
                stack.append(("function", header_line, name[0] if name else "?"))
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


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    parser.add_argument("--longest", type=int, default=5)
    args = parser.parse_args()
    root = os.path.abspath(args.root)
    errors = check_layers(root) + check_client_layers(root)
    length_errors, found = check_lengths(root)
    errors += length_errors
    print("longest functions:")
    for count, path, start, name in found[:args.longest]:
        print("  %4d lines  %s:%d  %s" % (count, path, start, name))
    for e in errors:
        print(e)
    print("structure: %d violation(s)" % len(errors))
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
