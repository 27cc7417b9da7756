#!/usr/bin/env python3
"""ctest soak_load_report: what scripts/soak.sh needs from `tactforce load`,
against a real tactforce-server on an ephemeral loopback port:
  * a 1 ms --deadline-ms still runs (the warm-up call gets >= 10 s), every
    call ends DEADLINE_EXCEEDED, and latency_all_us (every call, failed ones
    included) reports their time to completion while latency_us (successful
    calls only) stays empty;
  * a JSON list of PlanRequests as --request is sent round-robin (the
    server's info log shows both solvers of the list).

  load_report_test.py --source-dir ROOT --bin-dir DIR"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import unittest

ARGS = None


def setUpModule():
    sys.path.insert(0, os.path.join(ARGS.source_dir, "scripts", "soak"))


class LoadReportTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        from procs import Server
        cls.tmp = tempfile.TemporaryDirectory(prefix="soak-load-")
        cls.server = Server(ARGS.bin_dir, ["--log-level", "info"],
                            os.path.join(cls.tmp.name, "server.log"))
        cls.requests = os.path.join(ARGS.source_dir, "scripts", "soak")

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()
        cls.tmp.cleanup()

    def load(self, *args):
        run = subprocess.run([os.path.join(ARGS.bin_dir, "tactforce"), "load", "--target",
                              self.server.address, "--rpc", "plan", *args, "--json"],
                             capture_output=True, text=True, timeout=120)
        self.assertTrue(run.stdout.startswith("{"), f"exit {run.returncode}: {run.stderr}")
        return run.returncode, json.loads(run.stdout)

    def test_one_ms_deadline_reports_time_to_completion(self):
        code, report = self.load("--request", os.path.join(self.requests, "cylinder_4f_ipopt.json"),
                                 "--deadline-ms", "1", "-n", "8", "-c", "2")
        self.assertEqual(code, 4, report)  # the CLI's deadline-exceeded exit code
        self.assertEqual(report["requests"], 8)
        self.assertEqual(report["ok"], 0)
        self.assertEqual(report["errors"], {"DEADLINE_EXCEEDED": 8})
        self.assertEqual(report["latency_us"]["max"], 0)
        done = report["latency_all_us"]
        self.assertGreaterEqual(done["p50"], 900)  # ~1 ms each (histogram rounding aside)
        self.assertLessEqual(done["p50"], done["p90"])
        self.assertLessEqual(done["p90"], done["p99"])
        self.assertLessEqual(done["p99"], done["max"])

    def test_request_list_is_sent_round_robin(self):
        before = os.path.getsize(self.server.log_path)
        code, report = self.load("--request", os.path.join(self.requests, "overload_requests.json"),
                                 "-n", "8")
        self.assertEqual(code, 0, report)
        self.assertEqual(report["ok"], 8)
        self.assertEqual(report["errors"], {})
        # With no failures the two latency summaries agree.
        self.assertEqual(report["latency_all_us"]["max"], report["latency_us"]["max"])
        with open(self.server.log_path) as f:
            f.seek(before)
            log = f.read()
        self.assertIn("solver=IPOPT", log)
        self.assertIn("solver=CROSS_CHECK", log)


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--source-dir", required=True)
    parser.add_argument("--bin-dir", required=True)
    ARGS, rest = parser.parse_known_args()
    unittest.main(argv=[sys.argv[0], *rest], verbosity=2)
