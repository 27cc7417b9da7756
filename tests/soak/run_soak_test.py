#!/usr/bin/env python3
"""ctest soak_summary: runs `scripts/soak.sh all --duration-scale S --bin DIR
--out TMP.json` and checks the summary with check_summary.py (structure,
servers survived, health SERVING, zero soak errors; not timings or RSS
growth, which a run this short cannot judge). The script's own exit 1 (a
criterion such as RSS growth failed) is therefore accepted; any other
non-zero exit fails the test.

  run_soak_test.py --source-dir ROOT --bin-dir DIR [--scale 0.05]"""

import argparse
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import check_summary  # noqa: E402


def main(argv):
    p = argparse.ArgumentParser()
    p.add_argument("--source-dir", required=True)
    p.add_argument("--bin-dir", required=True)
    p.add_argument("--scale", default="0.05")
    args = p.parse_args(argv)
    script = os.path.join(args.source_dir, "scripts", "soak.sh")
    with tempfile.TemporaryDirectory(prefix="soak-test-") as tmp:
        out = os.path.join(tmp, "summary.json")
        run = subprocess.run([script, "all", "--duration-scale", args.scale,
                              "--bin", args.bin_dir, "--out", out],
                             capture_output=True, text=True, timeout=300)
        print(run.stdout, end="")
        print(run.stderr, end="", file=sys.stderr)
        if run.returncode not in (0, 1) or not os.path.exists(out):
            print(f"run_soak_test: soak.sh exited {run.returncode} without a summary",
                  file=sys.stderr)
            return 1
        return check_summary.main([out])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
