#!/usr/bin/env python3
"""Writes the seed corpora of tests/fuzz/corpus/<target>/ (small, meaningful
inputs from client/examples and handwritten cases). Run from anywhere:
  python3 tests/fuzz/gen_corpus.py
Needs protoc (binary PlanRequests). Files it does not name are left alone
(e.g. units merged in by scripts/fuzz.sh --merge, reproducers)."""
import json
import math
import os
import struct
import subprocess

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
EXAMPLES = os.path.join(ROOT, "client", "examples")
CORPUS = os.path.join(HERE, "corpus")


def write(target, name, data):
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def example(name):
    with open(os.path.join(EXAMPLES, name), "rb") as f:
        return f.read()


def contact(name, p, n, mu=0.8, sigma=0.2, kind=None, **extra):
    c = {"name": name, "position": dict(zip("xyz", p)), "normal": dict(zip("xyz", n)),
         "friction": mu, "sigma": sigma}
    if kind:
        c["kind"] = kind
    c.update(extra)
    return c


def plan_requests():
    pinch = json.loads(example("sphere_pinch.json"))
    tri = {"object": {"mass": 0.3, "com": {"z": 0.01}},
           "contacts": [contact("a", (0.04, 0, 0), (-1, 0, 0)),
                        contact("b", (-0.02, 0.0346, 0), (0.5, -0.866, 0)),
                        contact("c", (-0.02, -0.0346, 0), (0.5, 0.866, 0), min_normal_force=0.5,
                                max_normal_force=20)],
           "cone": "CONE_MODEL_PYRAMID", "cone_sides": 8, "confidence": 2.0}
    table = {"object": {"mass": 1.0, "gravity": {"z": -9.81}, "inertia": {"ixx": 1e-3, "iyy": 1e-3, "izz": 1e-3}},
             "contacts": [contact("table", (0, 0, -0.05), (0, 0, 1), mu=0.5, kind="CONTACT_KIND_EXTRINSIC"),
                          contact("finger", (0, 0, 0.05), (0, 0, -1), mu=0.6, sigma=0.5)],
             "externalWrench": {"force": {"x": 0.2}, "torque": {"z": 0.01}},
             "solver": "SOLVER_GEOMETRIC", "solverOptions": {"rankTolerance": 1e-8}}
    infeasible = json.loads(json.dumps(pinch))
    for c in infeasible["contacts"]:
        c["friction"] = 0.05
    ipopt = json.loads(json.dumps(tri))
    ipopt.update({"solver": "SOLVER_CROSS_CHECK", "cone": "CONE_MODEL_EXACT",
                  "solver_options": {"ipopt_tolerance": 1e-9, "ipopt_max_iterations": 50}})
    return {"sphere_pinch": pinch, "tripod": tri, "table_extrinsic": table,
            "infeasible_low_friction": infeasible, "cross_check_exact": ipopt}


def text_proto(value, indent=""):
    """JSON-like dict -> protobuf text format (enough for these requests)."""
    snake = {"externalWrench": "external_wrench", "solverOptions": "solver_options",
             "rankTolerance": "rank_tolerance"}
    out = []
    for k, v in value.items():
        k = snake.get(k, k)
        for item in (v if isinstance(v, list) else [v]):
            if isinstance(item, dict):
                out.append(f"{indent}{k} {{\n{text_proto(item, indent + '  ')}{indent}}}\n")
            elif isinstance(item, str) and item.isupper():
                out.append(f"{indent}{k}: {item}\n")
            elif isinstance(item, str):
                out.append(f"{indent}{k}: {json.dumps(item)}\n")
            else:
                out.append(f"{indent}{k}: {item!r}\n")
    return "".join(out)


def plan_corpora():
    proto_dir = os.path.join(ROOT, "proto")
    for name, req in plan_requests().items():
        write("plan_json", f"P_{name}.json", "P" + json.dumps(req, indent=1))
        binary = subprocess.run(["protoc", f"-I{proto_dir}", "--encode=tactforce.v1.PlanRequest",
                                 "tactforce/v1/planner.proto"], input=text_proto(req).encode(),
                                check=True, capture_output=True).stdout
        write("plan_binary", f"{name}.bin", binary)
    write("plan_binary", "empty.bin", b"")
    write("plan_json", "P_unknown_field.json", 'P{"object": {"mas": 1}}')
    write("plan_json", "P_syntax_error.json", 'P{"contacts": [{"position": {"x": 1e999}},]')
    write("plan_json", "E_estimate_request.json", b"E" + example("estimate_request.json"))
    est = {"object": {"mass": 0.3}, "contacts": plan_requests()["tripod"]["contacts"],
           "readings": [2.0, 1.5, -0.1], "method": "ESTIMATE_METHOD_PROJECTION", "origin_weight": 0.01,
           "cone_sides": 6}
    write("plan_json", "E_projection_tripod.json", "E" + json.dumps(est))


def csv_corpora():
    rows = ["t,fx,fy,fz,px,py,pz,slip"]
    for i in range(30):
        t = i * 0.01
        fz = 3.0 - 0.1 * i
        slip = 1 if fz < 1.6 else 0
        rows.append(f"{t:.2f},1.0,0.0,{fz:.3f},{0.001 * slip * (i - 14):.4f},0,0,{slip}")
    write("csv", "0_friction.csv", "0" + "\n".join(rows) + "\n")
    write("csv", "H_friction_nan.csv", "Ht,fx,fy,fz,px,py,pz\n0,1,0,3,0,0,0\n0.01,,0,2.9,0,0,0\n0.02,1,0,nan,0,0,0\n")
    rows = ["t,reference,reading,shear,trial"]
    for i in range(60):
        t = i * 0.01
        ref = 5 * math.sin(math.pi * i / 30) ** 2
        rows.append(f"{t:.2f},{ref:.4f},{0.92 * max(ref - 0.15, 0) + 0.05:.4f},{0.1 * ref:.4f},{i // 30}")
    write("csv", "1_audit.csv", "1" + "\n".join(rows) + "\n")
    write("csv", "1_audit_short.csv", "1t,reference,reading\n0,1,1\n0.1,2,2\n")
    log = example("inertia_log.csv").decode().splitlines()
    write("csv", "2_inertia_contacts.csv", "2" + "\n".join(log[:13]) + "\n")
    rows = ["t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz"]
    for i in range(12):
        a = 0.1 * i
        rows.append(f"{0.02 * i:.2f},0,0,{0.01 * i:.3f},{math.cos(a / 2):.6f},0,0,{math.sin(a / 2):.6f},"
                    f"0,0,{4.9 + 0.1 * i:.3f},0.01,0,0")
    write("csv", "2_inertia_wrench.csv", "2" + "\n".join(rows) + "\n")


def magnitude_corpora():
    """Issue 23's huge finite inputs and corrupt stream bytes: each request
    path must refuse them by name, never answer OK with a wrong number."""
    tripod = plan_requests()["tripod"]
    huge = json.loads(json.dumps(tripod))
    huge["contacts"][0]["normal"] = {"x": 0, "y": 0, "z": -1e155}
    write("plan_json", "P_normal_1e155.json", "P" + json.dumps(huge))
    huge["contacts"][0]["normal"] = {"x": 0, "y": 0, "z": -1}
    huge["contacts"][1]["friction"] = "Infinity"
    write("plan_json", "P_friction_infinity.json", "P" + json.dumps(huge))
    est = {"object": {"mass": 0.3}, "contacts": tripod["contacts"], "readings": [2.0, 1e300, -0.1]}
    write("plan_json", "E_reading_1e300.json", "E" + json.dumps(est))
    # A length-delimited field declaring 4 GiB (the corrupt stream message).
    write("plan_binary", "corrupt_field_4gib.bin", b"\x12\xff\xff\xff\x0f")
    rows = ["t,fx,fy,fz,px,py,pz,slip"]
    for i in range(20):
        slip = 1 if i > 12 else 0
        rows.append(f"{i * 0.01:.2f},1e155,0,{3e155 - 1e154 * i:.3e},{0.001 * slip * (i - 12):.4f},0,0,{slip}")
    write("csv", "0_friction_forces_1e155.csv", "0" + "\n".join(rows) + "\n")
    rows = ["t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz"]
    for i in range(12):
        rows.append(f"{1e-300 * i:.3e},0,0,{1e300 * i:.3e},1,0,0,0,0,0,{4.9e300:.3e},0.01,0,0")
    write("csv", "2_inertia_times_1e-300_wrench_1e300.csv", "2" + "\n".join(rows) + "\n")


def mesh_corpora():
    write("mesh", "0_probe_block.stl", b"0" + example("probe_block.stl"))
    write("mesh", "0_inertia_box_binary.stl", b"0" + example("inertia_box.stl"))
    tet = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    stl = ["solid tet"]
    for f in faces:
        stl += ["facet normal 0 0 0", " outer loop"] + [f"  vertex {' '.join(map(str, tet[i]))}" for i in f]
        stl += [" endloop", "endfacet"]
    write("mesh", "0_tet_ascii.stl", "0" + "\n".join(stl + ["endsolid tet"]) + "\n")
    binary = bytearray(b"fuzz tet".ljust(80, b" ")) + struct.pack("<I", len(faces))
    for f in faces:
        binary += struct.pack("<3f", 0, 0, 0)
        for i in f:
            binary += struct.pack("<3f", *tet[i])
        binary += struct.pack("<H", 0)
    write("mesh", "0_tet_binary.stl", b"0" + bytes(binary))
    obj = ["# tet", *[f"v {x} {y} {z}" for x, y, z in tet], "vn 0 0 1",
           *[f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces], "f 1/1/1 2/1/1 3/1/1 4/1/1"]
    write("mesh", "1_tet.obj", "1" + "\n".join(obj) + "\n")
    ply = ["ply", "format ascii 1.0", "element vertex 4", "property float x", "property float y",
           "property float z", "element face 4", "property list uchar int vertex_indices",
           "property uchar red", "property uchar green", "property uchar blue", "end_header",
           *[f"{x} {y} {z}" for x, y, z in tet], *[f"3 {a} {b} {c} 200 {40 * k} 10" for k, (a, b, c) in enumerate(faces)]]
    write("mesh", "2_tet_colors.ply", "2" + "\n".join(ply) + "\n")
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n").encode()
    body = b"".join(struct.pack("<3f", *v) for v in tet)
    body += b"".join(struct.pack("<B3i", 3, *f) for f in faces)
    write("mesh", "2_tet_binary.ply", b"2" + head + body)
    mesh_count_corpora(tet, faces)


def mesh_count_corpora(tet, faces):
    """Issue 23: declared counts that made assimp allocate gigabytes (PLY
    element counts and list lengths, binary STL triangle counts), files named
    by an OBJ (mtllib), and a binary PLY body starting with a newline byte."""
    box = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
    quads = [(0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3), (0, 2, 3, 1), (4, 5, 7, 6)]
    tris = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]

    def ply_head(fmt, vertices, triangles, extra=""):
        return (f"ply\nformat {fmt} 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\n"
                f"property float z\nelement face {triangles}\nproperty list uchar int vertex_indices\n{extra}"
                "end_header\n")

    ascii_body = "".join(f"{x} {y} {z}\n" for x, y, z in box) + "".join(f"3 {a} {b} {c}\n" for a, b, c in tris)
    write("mesh", "2_ply_ascii_vertex_count_1e8.ply", "2" + ply_head("ascii", 100000000, 12) + ascii_body)
    binary_body = b"".join(struct.pack("<3f", *v) for v in box) + b"".join(struct.pack("<B3i", 3, *t) for t in tris)
    for name, vertices, triangles in (("face_count_1e8", 8, 100000000), ("vertex_count_2e9", 2000000000, 12)):
        write("mesh", f"2_ply_binary_{name}.ply",
              b"2" + ply_head("binary_little_endian", vertices, triangles).encode() + binary_body)
    extra = "element material 5000000000000\nproperty uchar id\nproperty list uint float w\n"
    write("mesh", "2_ply_extra_element_huge_count.ply",
          b"2" + ply_head("binary_little_endian", 8, 12, extra).encode() + binary_body + b"\x01\x00\x00\x00\x00")
    list_bomb = b"".join(struct.pack("<3f", *v) for v in tet) + struct.pack("<I3i", 4000000000, 0, 1, 2)
    write("mesh", "2_ply_binary_list_length_4e9.ply",
          b"2" + ply_head("binary_little_endian", 4, 1).replace("uchar int", "uint int").encode() + list_bomb)
    write("mesh", "2_ply_ascii_list_length_negative.ply",
          "2" + ply_head("ascii", 4, 1).replace("uchar int", "char int") +
          "".join(f"{x} {y} {z}\n" for x, y, z in tet) + "-1 0 1 2\n")
    newline_first = struct.pack("<I", 0x3f80000a) + binary_body[4:]  # x of vertex 0 ends in byte 0x0a
    write("mesh", "2_ply_binary_body_starts_with_newline.ply",
          b"2" + ply_head("binary_little_endian", 8, 12).encode() + newline_first)
    obj = ["mtllib /etc/hostname", "mtllib ../../../../etc/passwd", "mtllib box.mtl", "usemtl red",
           *[f"v {x} {y} {z}" for x, y, z in tet], "usemtl missing",
           *[f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]]
    write("mesh", "1_obj_mtllib_usemtl.obj", "1" + "\n".join(obj) + "\n")
    facet = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
    for name, count in (("wraps_32bit", 2**31 + 1), ("too_large", 1000)):
        stl = b"binary".ljust(80, b" ") + struct.pack("<I", count) + facet
        write("mesh", f"0_stl_binary_count_{name}.stl", b"0" + stl)


def sensor_model_corpora():
    write("sensor_model", "example.json", example("sensor_model.json"))
    full = {"format": "tactforce.sensor_model.v1", "units": "counts", "gain": -3.5, "offset": 12,
            "noise": 0.01, "partial_error": 0.02, "threshold": 0.1, "threshold_shift": 0.5,
            "delay": -0.01, "lag": 0.02, "saturation": 15, "curvature": 0.03, "full_scale": 20,
            "drift": 0.001, "crosstalk": 0.05, "power_exponent": 1.1,
            "uncertainty": {"gain": 0.01, "offset": None}, "source": "audit of run.csv",
            "effects_named": ["lag"], "notes": ["x"]}
    write("sensor_model", "full.json", json.dumps(full, indent=1))
    pi = {"format": "tactforce.sensor_model.v1", "pi_thresholds": [0, 0.5, 1.0], "pi_weights": [1, 0.5, 0.25]}
    write("sensor_model", "prandtl_ishlinskii.json", json.dumps(pi))
    write("sensor_model", "hysteresis.json", '{"hysteresis_width": 0.4, "gain": 1.1}')
    write("sensor_model", "typo.json", '{"gian": 1}')
    write("sensor_model", "not_object.json", '[1, 2]')


if __name__ == "__main__":
    plan_corpora()
    csv_corpora()
    magnitude_corpora()
    mesh_corpora()
    sensor_model_corpora()
