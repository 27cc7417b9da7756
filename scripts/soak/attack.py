"""What one hostile request can make tactforce-server hold and how fast it
lets go (scripts/soak.sh memory | stops), through the Python stubs the build
generates (build/python), each case on a fresh server with default flags.

memory: the server's peak RSS (VmHWM) above its RSS before the call, for the
  issue-23 mesh reproducers (PLY header counts of 1e8, binary and ASCII) and
  the largest meshes a 4 MiB message can carry (a closed binary STL sphere
  fitted with DENSITY, and an OBJ of tiny faces), plus a FitInertia stream
  at the server's byte budget.
stops: how long after its deadline (or after SIGTERM with --grace-ms 1000,
  sent 1 s into the call) the server ends a long call: a DENSITY fit with the
  most regions allowed, a long Ipopt trajectory (1 s deadlines) and a slow
  Ipopt plan (10 ms deadline)."""

import csv
import math
import os
import signal
import struct
import sys
import threading
import time

from procs import Server, read_cpu_seconds, read_proc_status_kb

GRACE_MS = 1000
MAX_TARGET_REGIONS = 100  # inertia::kMaxTargetRegions


def stubs(cfg):
    sys.path.insert(0, os.path.join(os.path.dirname(cfg.bin), "python"))
    import grpc  # noqa: E402
    from tactforce.v1 import (estimator_pb2, estimator_pb2_grpc, inertia_pb2,  # noqa: E402
                              planner_pb2, planner_pb2_grpc)
    return grpc, estimator_pb2, estimator_pb2_grpc, inertia_pb2, planner_pb2, planner_pb2_grpc


def log_samples(inertia_pb2, path):
    """client/examples/inertia_log.csv as InertiaSample messages (4 contacts)."""
    out = []
    with open(path) as f:
        for row in csv.DictReader(f):
            s = inertia_pb2.InertiaSample(t=float(row["t"]))
            s.position.x, s.position.y, s.position.z = (float(row[k]) for k in ("px", "py", "pz"))
            q = s.orientation
            q.w, q.x, q.y, q.z = (float(row[k]) for k in ("qw", "qx", "qy", "qz"))
            for c in range(4):
                contact = s.contacts.add()
                p, fo = contact.point, contact.force
                p.x, p.y, p.z = (float(row[f"c{c}_p{a}"]) for a in "xyz")
                fo.x, fo.y, fo.z = (float(row[f"c{c}_f{a}"]) for a in "xyz")
            out.append(s)
    return out


def sphere_stl(rings, radius=0.05):
    """A closed UV sphere as binary STL (2 * rings^2 triangles, outward)."""
    def point(i, j):  # exact poles and seam, so shared vertices weld
        if i in (0, rings):
            return (0.0, 0.0, radius if i == 0 else -radius)
        th, ph = math.pi * i / rings, 2 * math.pi * (j % rings) / rings
        return (radius * math.sin(th) * math.cos(ph), radius * math.sin(th) * math.sin(ph),
                radius * math.cos(th))
    tris = []
    for i in range(rings):
        for j in range(rings):
            a, b = point(i, j), point(i + 1, j)
            c, d = point(i + 1, j + 1), point(i, j + 1)
            if i > 0:
                tris.append((a, b, d))
            if i < rings - 1:
                tris.append((b, c, d))
    body = b"".join(struct.pack("<12fH", 0, 0, 0, *t[0], *t[1], *t[2], 0) for t in tris)
    return b"\0" * 80 + struct.pack("<I", len(tris)) + body


def tiny_faces_obj(limit_bytes):
    lines = [b"v 0 0 0\n", b"v 1 0 0\n", b"v 0 1 0\n"]
    size = sum(map(len, lines))
    face = b"f 1 2 3\n"
    count = (limit_bytes - size) // len(face)
    return b"".join(lines) + face * count


def ply_declared(binary):
    if binary:
        head = (b"ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty float x\n"
                b"property float y\nproperty float z\nelement face 100000000\n"
                b"property list uchar int vertex_indices\nend_header\n")
        verts = b"".join(struct.pack("<3f", x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1))
        return head + verts + struct.pack("<B3i", 3, 0, 1, 2) * 12
    head = (b"ply\nformat ascii 1.0\nelement vertex 100000000\nproperty float x\nproperty float y\n"
            b"property float z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n")
    verts = b"".join(f"{x} {y} {z}\n".encode() for x in (0, 1) for y in (0, 1) for z in (0, 1))
    return head + verts + b"3 0 1 2\n" * 12


def mesh_cases():
    return [
        ("PLY ascii, element vertex 1e8 (391 B)", "ply", ply_declared(False), {}),
        ("PLY binary, element face 1e8 (429 B)", "ply", ply_declared(True), {}),
        ("closed STL sphere, 4 MB (80k triangles), DENSITY", "stl", sphere_stl(200), {}),
        ("OBJ of tiny faces, 4 MB", "obj", tiny_faces_obj(4_000_000), {}),
    ]


def fit_call(mods, channel, samples, mesh=None, method=None, regions=None, deadline_s=120):
    grpc, est_pb2, est_grpc, inertia_pb2, _, _ = mods
    options = inertia_pb2.InertiaFitOptions()
    if method is not None:
        options.method = method
    if regions is not None:
        options.target_regions = regions
    if mesh is not None:
        fmt, data = mesh
        options.mesh.format, options.mesh.data, options.mesh.name = fmt, data, f"mesh.{fmt}"
    first = inertia_pb2.FitInertiaRequest(options=options)
    first.samples.extend(samples)
    stub = est_grpc.EstimatorStub(channel)
    return timed_call(grpc, lambda: stub.FitInertia(iter([first]), timeout=deadline_s))


def timed_call(grpc, call):
    """(code, seconds) of one RPC: "OK", or the gRPC code with the start of
    its message."""
    start = time.monotonic()
    try:
        call()
        code = "OK"
    except grpc.RpcError as e:
        code = f"{e.code().name} ({e.details()[:100]})"
    return code, time.monotonic() - start


def run_memory(cfg):
    mods = stubs(cfg)
    grpc, inertia_pb2 = mods[0], mods[3]
    samples = log_samples(inertia_pb2, os.path.join(cfg.root, "client/examples/inertia_log.csv"))
    rows = []
    for name, fmt, data, _ in mesh_cases():
        server = Server(cfg.bin, [], os.path.join(cfg.work, "memory-server.log"))
        before = read_proc_status_kb(server.pid, "VmRSS")
        channel = grpc.insecure_channel(server.address)
        code, seconds = fit_call(mods, channel, samples, mesh=(fmt, data))
        peak = read_proc_status_kb(server.pid, "VmHWM")
        channel.close()
        rows.append({"case": name, "request_bytes": len(data), "code": code,
                     "seconds": round(seconds, 2), "rss_before_kb": before,
                     "peak_above_start_kb": None if peak is None or before is None else peak - before,
                     "server_exit_code": server.stop()})
    out = {"cases": rows}
    out["pass"] = all(r["server_exit_code"] == 0 for r in rows)
    return out


def stop_cases(mods, cfg, samples):
    _, _, _, inertia_pb2, planner_pb2, planner_grpc = mods
    box = ("stl", open(os.path.join(cfg.root, "client/examples/inertia_box.stl"), "rb").read())
    regions = MAX_TARGET_REGIONS
    density = inertia_pb2.INERTIA_METHOD_DENSITY
    traj = planner_pb2.TrajectoryRequest()
    with open(os.path.join(cfg.root, "client/examples/wrench_lift_trajectory.json")) as f:
        from google.protobuf import json_format
        json_format.Parse(f.read(), traj)
    traj.plan.solver = planner_pb2.SOLVER_IPOPT
    base = list(traj.steps)
    while len(traj.steps) < 3000:
        traj.steps.extend(base)
    plan = planner_pb2.PlanRequest()
    with open(os.path.join(cfg.root, "scripts/soak/lane_ipopt_64.json")) as f:
        json_format.Parse(f.read(), plan)

    def density_fit(channel, deadline):
        return fit_call(mods, channel, samples, mesh=box, method=density, regions=regions,
                        deadline_s=deadline)

    def unary(method, request):
        def call(channel, deadline):
            fn = getattr(planner_grpc.PlannerStub(channel), method)
            return timed_call(mods[0], lambda: fn(request, timeout=deadline))
        return call
    return [(f"FitInertia DENSITY, box mesh, target_regions {regions}", density_fit, 1.0),
            (f"PlanTrajectory IPOPT, {len(traj.steps)} steps", unary("PlanTrajectory", traj), 1.0),
            ("Plan IPOPT, 64 contacts, exact cones", unary("Plan", plan), 0.01)]


def sigterm_stop(cfg, mods, call):
    """Seconds from SIGTERM (1 s into the call) to the server's exit, with
    --grace-ms GRACE_MS, and the server's exit code."""
    server = Server(cfg.bin, ["--grace-ms", str(GRACE_MS)], os.path.join(cfg.work, "stops-server.log"))
    channel = mods[0].insecure_channel(server.address)
    worker = threading.Thread(target=call, args=(channel, 300), daemon=True)
    worker.start()
    time.sleep(1.0)
    start = time.monotonic()
    server.proc.send_signal(signal.SIGTERM)
    try:
        code = server.proc.wait(60)
    except Exception:  # noqa: BLE001 - a server that does not stop is the finding
        server.kill()
        code = None
    elapsed = time.monotonic() - start
    channel.close()
    return code, elapsed


def run_stops(cfg):
    mods = stubs(cfg)
    samples = log_samples(mods[3], os.path.join(cfg.root, "client/examples/inertia_log.csv"))
    rows = []
    for name, call, deadline_s in stop_cases(mods, cfg, samples):
        server = Server(cfg.bin, [], os.path.join(cfg.work, "stops-server.log"))
        channel = mods[0].insecure_channel(server.address)
        code, seconds = call(channel, deadline_s)
        # Does the server keep computing after the caller has given up?
        cpu_before = read_cpu_seconds(server.pid) or 0.0
        time.sleep(1.0)
        cpu_after_s = (read_cpu_seconds(server.pid) or 0.0) - cpu_before
        channel.close()
        server.stop()
        exit_code, term_s = sigterm_stop(cfg, mods, call)
        rows.append({"case": name, "deadline_s": deadline_s, "code": code,
                     "after_deadline_s": round(seconds - deadline_s, 3),
                     "server_cpu_s_in_1s_after": round(cpu_after_s, 3),
                     "grace_ms": GRACE_MS, "sigterm_to_exit_s": round(term_s, 3),
                     "sigterm_exit_code": exit_code})
    out = {"cases": rows}
    out["pass"] = all(r["after_deadline_s"] <= 1.0 and r["server_cpu_s_in_1s_after"] <= 0.5 and
                      r["sigterm_to_exit_s"] <= GRACE_MS / 1000 + 1.0
                      and r["sigterm_exit_code"] == 0 for r in rows)
    return out
