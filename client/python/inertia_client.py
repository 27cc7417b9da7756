#!/usr/bin/python3
"""Fit mass, centre of mass and inertia on a running tactforce-server.

Reads an inertia CSV (the format of `tactforce inertia --csv`, see the
README's data formats) and streams it to tactforce.v1.Estimator.FitInertia
in batches: the first message carries the options, every message a batch
of samples, so a long log is never one giant message. Prints the
FitInertiaResponse as JSON (proto field names) or a short summary.

    PYTHONPATH=build/python /usr/bin/python3 client/python/inertia_client.py \\
        --server 127.0.0.1:50051 --csv run.csv [--method factor-graph] \\
        [--truth truth.json] [--batch 500] [--json]

Uses Debian's python3-grpcio and python3-protobuf (hence /usr/bin/python3).
Only the columns tactforce documents are read; unknown columns are ignored.
Checks here are minimal (header, numbers); the server validates everything
else and names the sample ("samples[12].orientation: ...").

Exit codes: 0 fitted, 1 the RPC failed (unreachable server, deadline, ...),
2 bad command line, bad file or invalid request (INVALID_ARGUMENT).
"""

import argparse
import csv
import json
import math
import sys

from client_env import EXIT_BAD_INPUT, EXIT_OK, EXIT_RPC_FAILED, load

grpc, json_format, (estimator_pb2_grpc, inertia_pb2) = load("estimator_pb2_grpc", "inertia_pb2")

METHODS = {
    "baseline-ls": inertia_pb2.INERTIA_METHOD_BASELINE_LS,
    "factor-graph": inertia_pb2.INERTIA_METHOD_FACTOR_GRAPH,
    "constrained": inertia_pb2.INERTIA_METHOD_CONSTRAINED,
}

POSE = ["t", "px", "py", "pz", "qw", "qx", "qy", "qz"]
WRENCH = ["fx", "fy", "fz", "tx", "ty", "tz"]
KINEMATICS = ["wx", "wy", "wz", "dwx", "dwy", "dwz", "ax", "ay", "az"]


class BadInput(Exception):
    pass


def set_vec(message, values):
    message.x, message.y, message.z = values


def read_samples(path):
    """Checks the header now; returns a generator of InertiaSample messages,
    one per CSV row (a bad row raises BadInput while streaming)."""
    handle = open(path, newline="", encoding="utf-8")
    reader = csv.reader(handle)
    try:
        header = [name.strip() for name in next(reader)]
    except StopIteration:
        raise BadInput(f"{path}: empty (no header)") from None
    col = {name: i for i, name in enumerate(header)}
    missing = [name for name in POSE if name not in col]
    if missing:
        raise BadInput(f"{path}: missing column(s) {','.join(missing)}")
    contacts = 0
    while f"c{contacts}_fx" in col:
        contacts += 1
    if contacts == 0 and any(name not in col for name in WRENCH):
        raise BadInput(f"{path}: no force source: give fx..tz or c0_px..c0_fz")
    kinematics = all(name in col for name in KINEMATICS)
    return _rows(path, handle, reader, col, contacts, kinematics)


def _rows(path, handle, reader, col, contacts, kinematics):
    with handle:
        for line, row in enumerate(reader, start=2):
            def value(name):
                try:
                    v = float(row[col[name]])
                except (IndexError, ValueError):
                    raise BadInput(f"{path}:{line}: column '{name}': not a number") from None
                if not math.isfinite(v):
                    raise BadInput(f"{path}:{line}: column '{name}': not finite")
                return v

            sample = inertia_pb2.InertiaSample()
            sample.t = value("t")
            set_vec(sample.position, [value(n) for n in ("px", "py", "pz")])
            q = sample.orientation
            q.w, q.x, q.y, q.z = (value(n) for n in ("qw", "qx", "qy", "qz"))
            if contacts:
                for i in range(contacts):
                    c = sample.contacts.add()
                    set_vec(c.point, [value(f"c{i}_p{a}") for a in "xyz"])
                    set_vec(c.force, [value(f"c{i}_f{a}") for a in "xyz"])
                    if f"c{i}_sigma" in col:
                        c.sigma = value(f"c{i}_sigma")
            else:
                set_vec(sample.wrench.force, [value(n) for n in ("fx", "fy", "fz")])
                set_vec(sample.wrench.torque, [value(n) for n in ("tx", "ty", "tz")])
            if kinematics:
                k = sample.kinematics
                set_vec(k.angular_velocity, [value(n) for n in ("wx", "wy", "wz")])
                if all(n in col for n in ("vx", "vy", "vz")):
                    set_vec(k.velocity, [value(n) for n in ("vx", "vy", "vz")])
                set_vec(k.angular_acceleration, [value(n) for n in ("dwx", "dwy", "dwz")])
                set_vec(k.acceleration, [value(n) for n in ("ax", "ay", "az")])
            yield sample


def read_truth(path):
    with open(path, encoding="utf-8") as handle:
        truth = json.load(handle)
    params = inertia_pb2.InertialParameters()
    try:
        params.mass = float(truth["mass"])
        set_vec(params.com, [float(v) for v in truth["com"]])
        i = params.inertia
        i.ixx, i.iyy, i.izz, i.ixy, i.ixz, i.iyz = (float(v) for v in truth["inertia_com"])
    except (KeyError, TypeError, ValueError) as error:
        raise BadInput(f"{path}: needs mass, com [3], inertia_com [6] ({error})") from None
    return params, truth.get("gravity_world")


class RequestStream:
    """The request stream: options first, then batches of samples. Keeps
    the first BadInput raised while reading (gRPC only reports that the
    iteration failed)."""

    def __init__(self, samples, options, batch):
        self.samples, self.options, self.batch = samples, options, batch
        self.error = None

    def __iter__(self):
        try:
            yield from requests(self.samples, self.options, self.batch)
        except BadInput as error:
            self.error = error
            raise


def requests(samples, options, batch):
    message = inertia_pb2.FitInertiaRequest()
    message.options.CopyFrom(options)
    for sample in samples:
        message.samples.append(sample)
        if len(message.samples) == batch:
            yield message
            message = inertia_pb2.FitInertiaRequest()
    if len(message.samples) or message.HasField("options"):
        yield message


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--server", default="localhost:50051", help="HOST:PORT")
    parser.add_argument("--csv", required=True, help="inertia CSV")
    parser.add_argument("--method", choices=sorted(METHODS), default="constrained")
    parser.add_argument("--truth", help="truth JSON: the response carries the error metrics")
    parser.add_argument("--batch", type=int, default=500, help="samples per message")
    parser.add_argument("--deadline", type=float, default=120.0, help="seconds")
    parser.add_argument("--json", action="store_true", help="print the response as JSON")
    args = parser.parse_args()
    if args.batch < 1:
        parser.error("--batch: must be >= 1")

    options = inertia_pb2.InertiaFitOptions()
    options.method = METHODS[args.method]
    try:
        if args.truth:
            params, gravity = read_truth(args.truth)
            options.truth.CopyFrom(params)
            if gravity:
                set_vec(options.gravity, [float(v) for v in gravity])
        samples = read_samples(args.csv)
        with grpc.insecure_channel(args.server) as channel:
            stub = estimator_pb2_grpc.EstimatorStub(channel)
            stream = RequestStream(samples, options, args.batch)
            try:
                response = stub.FitInertia(iter(stream), timeout=args.deadline)
            except grpc.RpcError:
                if stream.error is not None:
                    raise stream.error from None
                raise
    except (BadInput, OSError, json.JSONDecodeError) as error:
        print(f"error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except grpc.RpcError as error:
        print(f"error: {error.code().name}: {error.details()}", file=sys.stderr)
        return EXIT_BAD_INPUT if error.code() == grpc.StatusCode.INVALID_ARGUMENT else EXIT_RPC_FAILED

    if args.json:
        print(json_format.MessageToJson(response, preserving_proto_field_name=True,
                                        including_default_value_fields=True))
    else:
        c, i = response.com, response.inertia
        print(f"mass: {response.mass:.6g} kg, com: ({c.x:.6g}, {c.y:.6g}, {c.z:.6g}) m")
        print(f"inertia about the CoM: Ixx {i.ixx:.6g}, Iyy {i.iyy:.6g}, Izz {i.izz:.6g}, "
              f"Ixy {i.ixy:.6g}, Ixz {i.ixz:.6g}, Iyz {i.iyz:.6g} kg m^2")
        print(f"physically consistent: {'yes' if response.physically_consistent else 'NO'}; "
              f"{response.samples_received} samples, {response.time_seconds * 1e3:.1f} ms")
        if response.HasField("errors"):
            e = response.errors
            print(f"errors: paper metric {e.paper_metric:.4g}, Riemannian {e.riemannian:.4g}, "
                  f"mass {e.mass_percent:.3g} %, CoM {e.com_mm:.3g} mm")
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
