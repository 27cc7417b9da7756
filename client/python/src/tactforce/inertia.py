"""Fit mass, centre of mass and inertia on a running tactforce-server.

Reads an inertia CSV (the format of `tactforce inertia --csv`, see the
README's data formats) and streams it to tactforce.v1.Estimator.FitInertia
in batches: the first message carries the options, every message a batch
of samples, so a long log is never one giant message. Prints the
FitInertiaResponse as JSON (proto field names) or a short summary.

    tactforce-inertia-py --server 127.0.0.1:50051 --csv run.csv \\
        [--method factor-graph] [--truth truth.json] [--batch 500] [--json]
    (or: python3 -m tactforce.inertia ...)

With the object's mesh (STL, OBJ or PLY in the object frame, metres, or a
descriptor JSON {"mesh": FILE, "scale": S, "object_in_mesh": {"position":
[x,y,z], "quaternion": [w,x,y,z]}}) the file's bytes travel in the first
message (MeshInput; at most the server's --max-message-bytes) and the
method defaults to density:

    tactforce-inertia-py --server HOST:PORT --csv Hammer.csv \\
        --mesh Hammer.mesh.json [--mesh-scale 0.001] [--regions grid]

Only the columns tactforce documents are read; unknown columns are ignored.
Checks here are minimal (header, numbers); the server validates everything
else and names the sample ("samples[12].orientation: ...").

Exit codes (those of the `tactforce` CLI): 0 fitted, 1 any other failure
(e.g. RESOURCE_EXHAUSTED: a mesh over the server's message limit), 2 bad
command line, bad file or invalid request (INVALID_ARGUMENT), 3 server
unreachable (UNAVAILABLE), 4 deadline exceeded.
"""

import argparse
import csv
import json
import math
import os
import sys

import grpc

from tactforce._cli import print_json, report, wire_choices
from tactforce._csv import BadInput
from tactforce.client import Client
from tactforce.errors import EXIT_BAD_INPUT, EXIT_OK, TactforceError
from tactforce.v1 import inertia_pb2

METHODS = wire_choices(inertia_pb2.InertiaMethod, "INERTIA_METHOD_")
REGIONS = wire_choices(inertia_pb2.RegionScheme, "REGION_SCHEME_")

MESH_FORMATS = {".stl": "stl", ".obj": "obj", ".ply": "ply"}

POSE = ["t", "px", "py", "pz", "qw", "qx", "qy", "qz"]
WRENCH = ["fx", "fy", "fz", "tx", "ty", "tz"]
KINEMATICS = ["wx", "wy", "wz", "dwx", "dwy", "dwz", "ax", "ay", "az"]




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


def parse_numbers(text, count, flag, what):
    tokens = text.split(",")
    if len(tokens) != count:
        raise BadInput(f"{flag}: expected {count} numbers {what} (got {len(tokens)} in '{text}')")
    values = []
    for token in tokens:
        try:
            value = float(token)
        except ValueError:
            raise BadInput(f"{flag}: '{token}' is not a number") from None
        if not math.isfinite(value):
            raise BadInput(f"{flag}: '{token}' is not finite")
        values.append(value)
    return values


def read_mesh(path, scale=None, pose=None):
    """MeshInput for --mesh: a mesh file (object frame, m) or a descriptor
    JSON; --mesh-scale / --mesh-pose replace the descriptor's values. The
    server reads, places and checks the mesh and names what is wrong."""
    mesh = inertia_pb2.MeshInput()
    if path.lower().endswith(".json"):
        with open(path, encoding="utf-8") as handle:
            try:
                descriptor = json.load(handle)
            except json.JSONDecodeError as error:
                raise BadInput(f"{path}: {error}") from None
        if not isinstance(descriptor, dict):
            raise BadInput(f"{path}: expected a JSON object")
        unknown = sorted(set(descriptor) - {"mesh", "scale", "object_in_mesh"})
        if unknown:
            raise BadInput(f"{path}: unknown key '{unknown[0]}' (expected mesh, scale, object_in_mesh)")
        if not isinstance(descriptor.get("mesh"), str) or not descriptor["mesh"]:
            raise BadInput(f"{path}: missing key 'mesh' (the mesh file, .stl, .obj or .ply)")
        file = os.path.join(os.path.dirname(path), descriptor["mesh"])
        try:
            if "scale" in descriptor:
                mesh.scale = float(descriptor["scale"])
            placement = descriptor.get("object_in_mesh", {})
            unknown = sorted(set(placement) - {"position", "quaternion"})
            if unknown:
                raise BadInput(f"{path}: object_in_mesh: unknown key '{unknown[0]}' (expected position, quaternion)")
            if "position" in placement:
                set_vec(mesh.position, [float(v) for v in placement["position"]])
            if "quaternion" in placement:
                q = mesh.orientation
                q.w, q.x, q.y, q.z = (float(v) for v in placement["quaternion"])
        except (TypeError, ValueError, AttributeError) as error:
            raise BadInput(f"{path}: bad scale or object_in_mesh ({error})") from None
    else:
        file = path
    extension = os.path.splitext(file)[1].lower()
    if extension not in MESH_FORMATS:
        raise BadInput(f"{file}: unknown mesh extension '{extension}' (expected .stl, .obj or .ply)")
    with open(file, "rb") as handle:
        mesh.data = handle.read()
    mesh.format = MESH_FORMATS[extension]
    mesh.name = os.path.basename(file)
    if scale is not None:
        mesh.scale = scale
    if pose is not None:
        set_vec(mesh.position, pose[:3])
        q = mesh.orientation
        q.w, q.x, q.y, q.z = pose[3:]
    return mesh


def requests(samples, options, batch):
    message = inertia_pb2.FitInertiaRequest()
    message.options.CopyFrom(options)
    if options.HasField("mesh"):
        # The mesh makes the options big: they travel alone, so that only
        # the mesh counts against the server's --max-message-bytes.
        yield message
        message = inertia_pb2.FitInertiaRequest()
    for sample in samples:
        message.samples.append(sample)
        if len(message.samples) == batch:
            yield message
            message = inertia_pb2.FitInertiaRequest()
    if len(message.samples) or message.HasField("options"):
        yield message


def parse_args(argv=None):
    parser = argparse.ArgumentParser(prog="tactforce-inertia-py", description=__doc__.split("\n\n")[0])
    parser.add_argument("--server", default="localhost:50051", help="HOST:PORT")
    parser.add_argument("--csv", required=True, help="inertia CSV")
    parser.add_argument("--method", choices=sorted(METHODS),
                        help="default: density with --mesh, else constrained")
    parser.add_argument("--mesh", help="object mesh: STL/OBJ/PLY (object frame, m) or descriptor JSON")
    parser.add_argument("--mesh-scale", type=float, help="mesh units to m (> 0), replaces the descriptor's")
    parser.add_argument("--mesh-pose", help="x,y,z,qw,qx,qy,qz: object frame in the mesh frame")
    parser.add_argument("--regions", choices=sorted(REGIONS), default="auto", help="density: region scheme")
    parser.add_argument("--target-regions", type=int, default=0, help="density, grid: about N regions (0 = 12)")
    parser.add_argument("--truth", help="truth JSON: the response carries the error metrics")
    parser.add_argument("--batch", type=int, default=500, help="samples per message")
    parser.add_argument("--deadline", type=float, default=120.0, help="seconds")
    parser.add_argument("--json", action="store_true", help="print the response as JSON")
    args = parser.parse_args(argv)
    if args.batch < 1:
        parser.error("--batch: must be >= 1")
    if args.mesh is None and (args.mesh_scale is not None or args.mesh_pose is not None):
        parser.error("--mesh-scale and --mesh-pose need --mesh")
    if args.mesh_scale is not None and not args.mesh_scale > 0:
        parser.error(f"--mesh-scale: must be > 0 (got {args.mesh_scale:g})")
    if not 0 <= args.target_regions <= 512:
        parser.error("--target-regions: must be in 1..512 (0 = 12)")
    return args


def fit_options(args):
    """InertiaFitOptions from the flags: the method, regions, the mesh file's
    bytes (--mesh) and the truth (--truth); BadInput names the file or flag."""
    options = inertia_pb2.InertiaFitOptions()
    method = args.method or ("density" if args.mesh else "constrained")
    options.method = METHODS[method]
    options.regions = REGIONS[args.regions]
    options.target_regions = args.target_regions
    if args.mesh:
        pose = parse_numbers(args.mesh_pose, 7, "--mesh-pose", "x,y,z,qw,qx,qy,qz") if args.mesh_pose else None
        options.mesh.CopyFrom(read_mesh(args.mesh, args.mesh_scale, pose))
    if args.truth:
        params, gravity = read_truth(args.truth)
        options.truth.CopyFrom(params)
        if gravity:
            set_vec(options.gravity, [float(v) for v in gravity])
    return options


def fit(args, options):
    """Streams --csv to Estimator.FitInertia; a bad row ends the stream with
    its BadInput (the Client re-raises the stream's own exception)."""
    samples = read_samples(args.csv)
    with Client(args.server, timeout=args.deadline) as client:
        return client.FitInertia(requests(samples, options, args.batch))


def mesh_hint(error, options):
    """For RESOURCE_EXHAUSTED with a mesh: the first message carries it."""
    if error.code != grpc.StatusCode.RESOURCE_EXHAUSTED or not options.HasField("mesh"):
        return ""
    return (f" (the first message carries the mesh {options.mesh.name}, {len(options.mesh.data)} bytes: "
            "start tactforce-server with a larger --max-message-bytes, or give a smaller mesh)")


def print_summary(response):
    c, i = response.com, response.inertia
    print(f"mass: {response.mass:.6g} kg, com: ({c.x:.6g}, {c.y:.6g}, {c.z:.6g}) m")
    print(f"inertia about the CoM: Ixx {i.ixx:.6g}, Iyy {i.iyy:.6g}, Izz {i.izz:.6g}, "
          f"Ixy {i.ixy:.6g}, Ixz {i.ixz:.6g}, Iyz {i.iyz:.6g} kg m^2")
    print(f"physically consistent: {'yes' if response.physically_consistent else 'NO'}; "
          f"{response.samples_received} samples, {response.time_seconds * 1e3:.1f} ms")
    if len(response.densities):
        realizable = "yes" if response.density_realizable else "NO"
        print(f"density-realizable: {realizable}; regulariser {response.density_regularization:.3g} "
              f"({response.density_regularization_rule})")
        for region in response.densities:
            print(f"  {region.label:<18} {region.density:10.5g} kg/m^3 (se {region.standard_error:.2g})  "
                  f"volume {region.volume:.4g} m^3")
    if response.mesh_contradicted:
        print(response.mesh_contradiction)
    if response.HasField("errors"):
        e = response.errors
        print(f"errors: paper metric {e.paper_metric:.4g}, Riemannian {e.riemannian:.4g}, "
              f"mass {e.mass_percent:.3g} %, CoM {e.com_mm:.3g} mm")


def main(argv=None):
    args = parse_args(argv)
    options = inertia_pb2.InertiaFitOptions()
    try:
        options = fit_options(args)
        response = fit(args, options)
    except (BadInput, OSError, json.JSONDecodeError) as error:
        print(f"error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except TactforceError as error:
        return report(error, mesh_hint(error, options))

    if args.json:
        print_json(response)
    else:
        print_summary(response)
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
