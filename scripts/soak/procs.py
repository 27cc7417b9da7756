"""Processes of a soak run: a local tactforce-server on an ephemeral loopback
port (its RSS, CPU time and stderr log), the once-a-second monitor (RSS
sample + `tactforce health`), and `tactforce load` runs with --json.
Standard library only."""

import json
import re
import os
import select
import signal
import subprocess
import threading
import time

LISTEN_PREFIX = "tactforce-server listening on "


class SetupError(Exception):
    """The run could not start (missing binary, server did not listen)."""


def read_proc_status_kb(pid, field):
    """VmRSS / VmHWM of `pid` in kB from /proc/PID/status; None once gone."""
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except (OSError, ValueError, IndexError):
        return None
    return None


def read_cpu_times(pid):
    """(user, system) CPU time of `pid` in seconds; None once gone."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            text = f.read()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()
    tick = os.sysconf("SC_CLK_TCK")
    return int(fields[11]) / tick, int(fields[12]) / tick  # utime, stime


def read_cpu_seconds(pid):
    """User + system CPU time of `pid` in seconds; None once gone."""
    times = read_cpu_times(pid)
    return None if times is None else times[0] + times[1]


class Server:
    """tactforce-server --listen 127.0.0.1:0 FLAGS; the bound address is read
    from its one stdout line, stderr goes to `log_path`. `prefix`: a command
    the server runs under (e.g. valgrind's), whose process is `pid`."""

    def __init__(self, bin_dir, flags, log_path, start_timeout_s=20.0, prefix=()):
        exe = os.path.join(bin_dir, "tactforce-server")
        if not os.access(exe, os.X_OK):
            raise SetupError(f"{exe}: not found or not executable (--bin)")
        self.flags = list(flags)
        self.log_path = log_path
        self._log = open(log_path, "w")
        self.proc = subprocess.Popen([*prefix, exe, "--listen", "127.0.0.1:0", *flags],
                                     stdout=subprocess.PIPE, stderr=self._log,
                                     stdin=subprocess.DEVNULL)
        self.pid = self.proc.pid
        self.address = self._read_address(start_timeout_s)

    def _read_address(self, timeout_s):
        deadline = time.monotonic() + timeout_s
        line = b""
        while not line.endswith(b"\n"):
            left = deadline - time.monotonic()
            ready, _, _ = select.select([self.proc.stdout], [], [], max(left, 0))
            chunk = os.read(self.proc.stdout.fileno(), 256) if ready else b""
            if not chunk:
                self.kill()
                raise SetupError(f"tactforce-server did not listen within {timeout_s:.0f} s "
                                 f"(exit {self.proc.poll()}): {self.log_tail()}")
            line += chunk
        text = line.decode(errors="replace").strip()
        if not text.startswith(LISTEN_PREFIX):
            self.kill()
            raise SetupError(f"unexpected server stdout line: {text!r}")
        return text[len(LISTEN_PREFIX):]

    def alive(self):
        return self.proc.poll() is None

    def rss_kb(self):
        return read_proc_status_kb(self.pid, "VmRSS")

    def peak_rss_kb(self):
        return read_proc_status_kb(self.pid, "VmHWM")

    def cpu_s(self):
        return read_cpu_seconds(self.pid)

    def log_tail(self, lines=5):
        try:
            with open(self.log_path, errors="replace") as f:
                return " | ".join(f.read().splitlines()[-lines:])
        except OSError:
            return ""

    def stop(self, timeout_s=20.0):
        """SIGTERM (the server drains and exits 0), SIGKILL after
        `timeout_s`; the exit code, -N for a signal, as Popen reports it."""
        if self.alive():
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout_s)
            except subprocess.TimeoutExpired:
                self.kill()
        self.proc.stdout.close()
        self._log.close()
        return self.proc.returncode

    def kill(self):
        if self.alive():
            self.proc.kill()
        self.proc.wait()


def check_health(tactforce, address, deadline_ms=2000):
    """(status, ms): SERVING, NOT_SERVING, ... or 'ERROR(exit N): message'."""
    start = time.monotonic()
    run = subprocess.run([tactforce, "health", "--server", address,
                          "--deadline-ms", str(deadline_ms)],
                         capture_output=True, text=True, timeout=deadline_ms / 1000 + 10)
    ms = (time.monotonic() - start) * 1000
    status = run.stdout.strip()
    if run.returncode != 0 and not status:
        err = run.stderr.strip().splitlines()
        status = f"ERROR(exit {run.returncode}): {err[-1] if err else ''}"
    return status, ms


class Monitor:
    """Once a second: the server's RSS (VmRSS) and, on its own thread, a
    `tactforce health` check (the next one starts a second after the last
    one started, or when it ends if it took longer)."""

    def __init__(self, server, tactforce, period_s=1.0):
        self.server = server
        self.tactforce = tactforce
        self.period_s = period_s
        self.t0 = time.monotonic()
        self.rss = []     # [t_s, kB]
        self.health = []  # [t_s, status, ms]
        self._stop = threading.Event()
        self._threads = [threading.Thread(target=self._sample_rss, daemon=True),
                         threading.Thread(target=self._check_health, daemon=True)]

    def start(self):
        self.t0 = time.monotonic()
        for t in self._threads:
            t.start()
        return self

    def _tick(self, k):
        """Sleeps until the k-th period after t0; False once stopped."""
        wait = self.t0 + k * self.period_s - time.monotonic()
        return not self._stop.wait(max(wait, 0))

    def _sample_rss(self):
        k = 0
        while True:
            kb = self.server.rss_kb()
            if kb is not None:
                self.rss.append([round(time.monotonic() - self.t0, 3), kb])
            k += 1
            if not self._tick(k):
                return

    def _check_health(self):
        k = 0
        while True:
            t = time.monotonic() - self.t0
            try:
                status, ms = check_health(self.tactforce, self.server.address)
            except (OSError, subprocess.SubprocessError) as error:
                status, ms = f"ERROR: {error}", 0.0
            self.health.append([round(t, 3), status, round(ms, 1)])
            k = max(k + 1, int((time.monotonic() - self.t0) / self.period_s))
            if not self._tick(k):
                return

    def stop(self):
        """Takes one last RSS sample, then ends both threads."""
        kb = self.server.rss_kb()
        if kb is not None:
            self.rss.append([round(time.monotonic() - self.t0, 3), kb])
        self._stop.set()
        for t in self._threads:
            t.join(timeout=15)

    def health_summary(self):
        statuses = [h[1] for h in self.health]
        bad = [h for h in self.health if h[1] != "SERVING"]
        return {"checks": len(statuses), "serving": len(statuses) - len(bad),
                "not_serving": bad[:20],
                "max_ms": round(max((h[2] for h in self.health), default=0.0), 1),
                "all_serving": bool(statuses) and not bad}


class Load:
    """`tactforce load --target ADDR ARGS --json` in the background (under
    `prefix`, e.g. valgrind, when given); result() waits and parses its one
    JSON line (printed even when calls failed)."""

    def __init__(self, tactforce, address, args, name, workdir, prefix=()):
        self.name = name
        self.argv = [*prefix, tactforce, "load", "--target", address, *args, "--json"]
        self._out = open(os.path.join(workdir, f"load-{name}.out"), "w+")
        self._err = open(os.path.join(workdir, f"load-{name}.err"), "w+")
        self.proc = subprocess.Popen(self.argv, stdout=self._out, stderr=self._err,
                                     stdin=subprocess.DEVNULL)

    def result(self, timeout_s):
        try:
            code = self.proc.wait(timeout_s)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            code = self.proc.wait()
        self._out.seek(0)
        self._err.seek(0)
        out, err = self._out.read(), self._err.read()
        self._out.close()
        self._err.close()
        report = None  # the JSON object that starts a line of stdout (pretty-printed)
        for start in (m.start() for m in re.finditer(r"^\{", out, re.M)):
            try:
                report, _ = json.JSONDecoder().raw_decode(out[start:])
            except json.JSONDecodeError:
                pass
        return {"exit_code": code, "report": report,
                "stderr": " | ".join(err.strip().splitlines()[-3:])}
