#!/usr/bin/env python3
"""Counts hand-written status unwraps and ad-hoc field-path prefixes per folder.
unwrap: `if (!x.ok()) return x;` / `return x.status();` (one line, or the return on the
next line(s), braces allowed).  prefix: a StrCat/StrFormat whose result embeds
`<status>.message()` after a literal ending in ": " (i.e. "path: message").
Usage: scripts/count_status_unwraps.py [--list] [--rev REV] [folder ...]   (run from the repo root; tracked .h/.cc only)"""
import re, subprocess, sys, collections
UNWRAP = re.compile(r'if \((?:[^;()]*(?:\([^;]*?\))?[^;()]*;\s*)?!(\w+)\.ok\(\)\)\s*\{?\s*return (?:std::move\()?\1\)?(?:\.status\(\))?;')
PREFIX = re.compile(r'StrCat\([^;]*?": ",\s*[\w.()>*-]*\.message\(\)\)|StrCat\([^;]*?\.message\(\)\)')
REV = sys.argv[sys.argv.index('--rev') + 1] if '--rev' in sys.argv else None
sh = lambda *a: subprocess.run(a, capture_output=True, text=True).stdout
files = [f for f in (sh('git', 'ls-tree', '-r', '--name-only', REV) if REV else sh('git', 'ls-files')).split()
         if f.endswith(('.cc', '.h'))]
read = (lambda f: sh('git', 'show', f'{REV}:{f}')) if REV else (lambda f: open(f).read())
LIST = '--list' in sys.argv
args = [a for i, a in enumerate(sys.argv[1:], 1) if a not in ('--list', '--rev') and sys.argv[i - 1] != '--rev']
folders = args or sorted({f.split('/')[0] for f in files if '/' in f})
tot = collections.Counter()
print(f"{'folder':<12}{'unwraps':>8}{'prefix':>8}{'PrependPath':>12}")
for d in folders:
  u = p = pp = 0
  for f in files:
    if not f.startswith(d + '/') or '/status_macros.' in f: continue
    t = read(f)
    for rx, name in ((UNWRAP, 'unwrap'), (PREFIX, 'prefix')):
      for m in rx.finditer(t):
        if LIST: print(f"  {name} {f}:{t.count(chr(10), 0, m.start()) + 1}: {' '.join(m.group(0).split())[:110]}")
        if name == 'unwrap': u += 1
        else: p += 1
    pp += len(re.findall(r'\bPrependPath\(', t))
  tot.update(u=u, p=p, pp=pp)
  print(f"{d:<12}{u:>8}{p:>8}{pp:>12}")
print(f"{'total':<12}{tot['u']:>8}{tot['p']:>8}{tot['pp']:>12}")
