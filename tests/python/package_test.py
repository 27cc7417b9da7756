"""The installed tactforce package against a live tactforce-server (run by
run_package_test.py with the venv's interpreter; TACTFORCE_TEST_SERVER is
the server's address). One call per RPC through tactforce.Client with a
sensible answer, the errors' exit codes (2 bad input, 3 unavailable,
4 deadline) and the command-line tools' exit codes."""

import json
import math
import os
import random
import re
import socket
import subprocess
import unittest
from pathlib import Path

import grpc
import tactforce
from tactforce.v1 import audit_pb2, estimator_pb2, inertia_pb2, planner_pb2

SERVER = os.environ["TACTFORCE_TEST_SERVER"]
SOURCE = Path(os.environ["TACTFORCE_TEST_SOURCE_DIR"])
VENV = Path(os.environ["TACTFORCE_TEST_VENV"])
TMP = Path(os.environ["TACTFORCE_TEST_TMP"])
SPHERE_PINCH = SOURCE / "client" / "examples" / "sphere_pinch.json"
LIFT = SOURCE / "client" / "examples" / "wrench_lift_trajectory.json"


def read_json(path):
    with open(path, encoding="utf-8") as handle:
        return json.load(handle)


def wrench_grasp():
    """The 3-finger wrench grasp (tactforce.plan's built-in request)."""
    from tactforce.plan import wrench_grasp as grasp
    return grasp()


def closed_port():
    """A loopback socket bound to an ephemeral port but not listening:
    connecting to it is refused while it stays open."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.bind(("127.0.0.1", 0))
    return sock


def set_vec(message, values):
    message.x, message.y, message.z = values


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def matvec(m, v):
    return [sum(m[i][j] * v[j] for j in range(3)) for i in range(3)]


def quat_rotate_inverse(q, v):
    """R(q)^T v for a unit quaternion q = (w, x, y, z)."""
    w, x, y, z = q
    r = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    return [sum(r[j][i] * v[j] for j in range(3)) for i in range(3)]


def quat_step(q, omega, dt):
    """q * exp(omega dt / 2), omega in the object frame."""
    angle = math.sqrt(sum(w * w for w in omega)) * dt
    if angle < 1e-15:
        return q
    axis = [w * dt / angle for w in omega]
    s, c = math.sin(angle / 2), math.cos(angle / 2)
    dq = (c, axis[0] * s, axis[1] * s, axis[2] * s)
    w1, x1, y1, z1 = q
    w2, x2, y2, z2 = dq
    out = (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
           w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)
    norm = math.sqrt(sum(v * v for v in out))
    return tuple(v / norm for v in out)


MASS, COM = 0.5, [0.02, -0.01, 0.03]
INERTIA_COM = [[2e-3, 1e-4, 0.0], [1e-4, 3e-3, -2e-4], [0.0, -2e-4, 4e-3]]


def inertia_samples(count=400, dt=0.01):
    """A noise-free tumbling object (MASS, COM, INERTIA_COM) with measured
    kinematics and the Newton-Euler wrench applied to it (object frame,
    torque about the origin)."""
    g = [0.0, 0.0, -9.81]
    cc = sum(c * c for c in COM)
    inertia_origin = [[INERTIA_COM[i][j] + MASS * ((cc if i == j else 0.0) - COM[i] * COM[j])
                       for j in range(3)] for i in range(3)]
    q = (1.0, 0.0, 0.0, 0.0)
    samples = []
    for k in range(count):
        t = k * dt
        omega = [1.5 * math.sin(1.1 * t), 1.2 * math.cos(0.7 * t), 0.9 * math.sin(0.5 * t + 0.3)]
        alpha = [1.65 * math.cos(1.1 * t), -0.84 * math.sin(0.7 * t), 0.45 * math.cos(0.5 * t + 0.3)]
        accel = [0.5 * math.sin(2.0 * t), 0.3 * math.cos(1.5 * t), 0.4 * math.sin(t)]
        a_obj = quat_rotate_inverse(q, [accel[i] - g[i] for i in range(3)])
        wxc = cross(omega, COM)
        force = [MASS * (a_obj[i] + cross(alpha, COM)[i] + cross(omega, wxc)[i]) for i in range(3)]
        i_omega = matvec(inertia_origin, omega)
        torque = [matvec(inertia_origin, alpha)[i] + cross(omega, i_omega)[i] + MASS * cross(COM, a_obj)[i]
                  for i in range(3)]
        s = inertia_pb2.InertiaSample(t=t)
        s.orientation.w, s.orientation.x, s.orientation.y, s.orientation.z = q
        set_vec(s.wrench.force, force)
        set_vec(s.wrench.torque, torque)
        set_vec(s.kinematics.angular_velocity, omega)
        set_vec(s.kinematics.angular_acceleration, alpha)
        set_vec(s.kinematics.acceleration, accel)
        samples.append(s)
        q = quat_step(q, omega, dt)
    return samples


def friction_request(mu=0.5, trials=3):
    """Probes pressing on a top face (normal (0,0,-1)) with a constant
    tangential force while the normal force ramps down: slip where the
    tangential force reaches mu times the normal force."""
    request = estimator_pb2.FrictionRequest()
    rate, ft, ramp = 200.0, 1.0, 0.5
    fn_slip = ft / mu
    for trial in range(trials):
        heading = 2 * math.pi * trial / trials
        tangent = [math.cos(heading), math.sin(heading), 0.0]
        fn0 = fn_slip * (1.3 + 0.05 * trial)
        t_slip = (fn0 - fn_slip) / ramp
        out = request.trials.add(name=f"trial{trial}")
        set_vec(out.normal, [0.0, 0.0, -1.0])
        for k in range(int((t_slip + 0.3) * rate)):
            t = k / rate
            fn = fn0 - ramp * t
            travel, f_t = 0.0, ft
            if t > t_slip:
                f_t = 0.8 * mu * fn
                travel = 0.02 * (t - t_slip)
            sample = out.samples.add(t=t)
            set_vec(sample.force, [f_t * tangent[0], f_t * tangent[1], -fn])
            set_vec(sample.contact_point, [travel * tangent[0], travel * tangent[1], 0.02])
    return request


def audit_request(threshold=0.3, seconds=15.0, rate=50.0):
    """A sensor that reads nothing below `threshold` N (a deadzone),
    against press-release cycles of a reference force; slight noise."""
    rng = random.Random(9)
    request = audit_pb2.AuditRequest(source="python-package-test")
    for k in range(int(seconds * rate)):
        t = k / rate
        phase = (t % 3.0) / 3.0
        reference = 4.0 * (2 * phase if phase < 0.5 else 2 - 2 * phase)
        reading = max(0.0, reference - threshold) + rng.gauss(0.0, 0.02)
        request.samples.add(t=t, reference=reference, reading=reading)
    return request


class PackageTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.client = tactforce.Client(SERVER, timeout=30)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()

    def test_installed_from_the_venv_with_the_cmake_version(self):
        self.assertTrue(Path(tactforce.__file__).resolve().is_relative_to(VENV.resolve()), tactforce.__file__)
        cmake = (SOURCE / "CMakeLists.txt").read_text(encoding="utf-8")
        version = re.search(r"project\s*\(\s*tactforce\s+VERSION\s+(\S+)", cmake).group(1)
        self.assertEqual(tactforce.__version__, version)
        stubs = {p.stem for p in (Path(tactforce.__file__).parent / "v1").glob("*_pb2.py")}
        protos = {p.stem + "_pb2" for p in (SOURCE / "proto" / "tactforce" / "v1").glob("*.proto")}
        self.assertEqual(stubs, protos)
        self.assertEqual(tactforce.HAS_SERVER_INFO, "info_pb2" in stubs)

    def test_plan_sphere_pinch(self):
        response = self.client.Plan(read_json(SPHERE_PINCH))
        self.assertEqual(response.status, planner_pb2.PLAN_STATUS_OPTIMAL, response.message)
        self.assertEqual(len(response.forces), 2)
        self.assertGreater(min(response.normal_forces), 0.0)
        # The forces hold the 82 g sphere against gravity.
        self.assertAlmostEqual(sum(f.z for f in response.forces), 0.082 * 9.81, delta=1e-3)

    def test_plan_stream_one_answer_per_request_in_order(self):
        requests = [wrench_grasp(), read_json(SPHERE_PINCH), wrench_grasp()]
        responses = list(self.client.PlanStream(iter(requests)))
        self.assertEqual([len(r.forces) for r in responses], [3, 2, 3])
        self.assertTrue(all(r.status == planner_pb2.PLAN_STATUS_OPTIMAL for r in responses))

    def test_plan_trajectory(self):
        response = self.client.PlanTrajectory(read_json(LIFT))
        self.assertEqual(len(response.steps), 4)
        self.assertEqual(response.optimal_steps, 4)
        self.assertTrue(all(len(step.forces) == 3 for step in response.steps))

    def test_plan_friction_probe(self):
        request = planner_pb2.FrictionProbeRequest()
        request.plan.CopyFrom(wrench_grasp())
        set_vec(request.position, [0.0, 0.0, 0.012])
        set_vec(request.normal, [0.0, 0.0, -1.0])
        set_vec(request.tangent, [1.0, 0.0, 0.0])
        request.tangential_force = 0.5
        request.initial_normal_force = 2.0
        request.final_normal_force = 1.0
        request.ramp_rate = 1.0
        request.sample_rate = 10.0
        response = self.client.PlanFrictionProbe(request)
        self.assertEqual(len(response.times), 11)
        self.assertEqual(len(response.probe_forces), 11)
        self.assertEqual(len(response.holding.steps), 11)
        self.assertAlmostEqual(response.probe_forces[0].z, -2.0)
        self.assertAlmostEqual(response.probe_forces[-1].z, -1.0)

    def test_estimate_forces_one_force_per_contact(self):
        grasp = wrench_grasp()
        request = estimator_pb2.EstimateRequest(readings=[2.0, 1.5, 3.5])
        request.object.CopyFrom(grasp.object)
        request.contacts.extend(grasp.contacts)
        response = self.client.EstimateForces(request)
        self.assertEqual(response.status, estimator_pb2.ESTIMATE_STATUS_OK, response.message)
        self.assertEqual(len(response.forces), 3)
        self.assertEqual(len(response.residuals), 3)

    def test_estimate_friction_recovers_mu(self):
        response = self.client.EstimateFriction(friction_request(mu=0.5, trials=3))
        self.assertEqual(response.count, 3)
        self.assertAlmostEqual(response.median, 0.5, delta=0.03)

    def test_fit_inertia_streams_batches(self):
        samples = inertia_samples()

        def requests():
            first = inertia_pb2.FitInertiaRequest()
            first.options.method = inertia_pb2.INERTIA_METHOD_BASELINE_LS
            yield first
            for k in range(0, len(samples), 64):
                yield inertia_pb2.FitInertiaRequest(samples=samples[k:k + 64])

        response = self.client.FitInertia(requests())
        self.assertEqual(response.samples_received, len(samples))
        self.assertAlmostEqual(response.mass, MASS, delta=1e-3 * MASS)
        self.assertAlmostEqual(response.com.x, COM[0], delta=1e-3)
        self.assertAlmostEqual(response.com.z, COM[2], delta=1e-3)

    def test_fit_inertia_reraises_the_request_streams_own_error(self):
        class BadRow(Exception):
            pass

        def requests():
            yield inertia_pb2.FitInertiaRequest(samples=inertia_samples(count=5))
            raise BadRow("row 7: not a number")

        with self.assertRaises(BadRow):
            self.client.FitInertia(requests())

    def test_audit_model(self):
        response = self.client.AuditModel(audit_request())
        self.assertTrue(response.summary)
        self.assertTrue(json.loads(response.report_json))
        self.assertFalse(response.nominal_adequate)
        self.assertGreaterEqual(len(response.causes), 1)
        self.assertEqual(response.causes[0].effect, "deadzone")

    @unittest.skipUnless(tactforce.HAS_SERVER_INFO, "built without tactforce/v1/info.proto")
    def test_get_server_info(self):
        try:
            info = self.client.GetServerInfo()
        except tactforce.TactforceError as error:
            if error.code == grpc.StatusCode.UNIMPLEMENTED:
                self.skipTest("this tactforce-server does not serve tactforce.v1.Info")
            raise
        self.assertEqual(info.version, tactforce.__version__)

    def test_invalid_request_is_exit_code_2(self):
        request = read_json(SPHERE_PINCH)
        request["contacts"][0]["normal"] = {}
        with self.assertRaises(tactforce.TactforceError) as caught:
            self.client.Plan(request)
        error = caught.exception
        self.assertEqual(error.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertEqual(error.exit_code, 2)
        self.assertEqual(error.method, "Plan")
        self.assertIn("contacts[0].normal", error.details)
        # A dict that is not a PlanRequest at all: bad input too.
        with self.assertRaises(tactforce.TactforceError) as caught:
            self.client.Plan({"no_such_field": 1})
        self.assertEqual(caught.exception.exit_code, 2)

    def test_unreachable_server_is_exit_code_3(self):
        sock = closed_port()
        try:
            with tactforce.Client(f"127.0.0.1:{sock.getsockname()[1]}", timeout=10) as client:
                with self.assertRaises(tactforce.TactforceError) as caught:
                    client.Plan(wrench_grasp())
                with self.assertRaises(tactforce.TactforceError) as streamed:
                    list(client.PlanStream([wrench_grasp()]))
        finally:
            sock.close()
        self.assertEqual(caught.exception.code, grpc.StatusCode.UNAVAILABLE)
        self.assertEqual(caught.exception.exit_code, 3)
        self.assertEqual(streamed.exception.exit_code, 3)

    def test_tiny_deadline_is_exit_code_4(self):
        self.client.Plan(wrench_grasp())  # connected
        with self.assertRaises(tactforce.TactforceError) as caught:
            self.client.AuditModel(audit_request(), timeout=1e-4)
        self.assertEqual(caught.exception.code, grpc.StatusCode.DEADLINE_EXCEEDED)
        self.assertEqual(caught.exception.exit_code, 4)

    def test_exit_codes_match_the_cli(self):
        codes = {grpc.StatusCode.OK: 0, grpc.StatusCode.INVALID_ARGUMENT: 2, grpc.StatusCode.UNAVAILABLE: 3,
                 grpc.StatusCode.DEADLINE_EXCEEDED: 4, grpc.StatusCode.INTERNAL: 1,
                 grpc.StatusCode.RESOURCE_EXHAUSTED: 1, grpc.StatusCode.UNIMPLEMENTED: 1}
        for code, exit_code in codes.items():
            self.assertEqual(tactforce.exit_code_for(code), exit_code, code)


class ToolsTest(unittest.TestCase):
    """tactforce-plan-py and tactforce-inertia-py, the console scripts."""

    def tool(self, name, *args):
        return subprocess.run([str(VENV / "bin" / name), *args], capture_output=True, text=True, timeout=60)

    def test_plan_tool_exit_codes(self):
        run = self.tool("tactforce-plan-py", "--server", SERVER, "--request", str(SPHERE_PINCH), "--json")
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertEqual(json.loads(run.stdout)["status"], "PLAN_STATUS_OPTIMAL")

        bad = TMP / "bad.json"
        bad.write_text('{"object": {"mass": 0.1}, "contacts": [{"normal": {}}]}', encoding="utf-8")
        run = self.tool("tactforce-plan-py", "--server", SERVER, "--request", str(bad))
        self.assertEqual(run.returncode, 2, run.stderr)
        self.assertIn("INVALID_ARGUMENT: contacts[0].normal", run.stderr)

        run = self.tool("tactforce-plan-py", "--server", SERVER, "--timeout", "0.0001", "--stream")
        self.assertEqual(run.returncode, 4, run.stderr)
        self.assertIn("DEADLINE_EXCEEDED", run.stderr)

        sock = closed_port()
        try:
            run = self.tool("tactforce-plan-py", "--server", f"127.0.0.1:{sock.getsockname()[1]}")
        finally:
            sock.close()
        self.assertEqual(run.returncode, 3, run.stderr)
        self.assertIn("UNAVAILABLE", run.stderr)

    def test_inertia_tool(self):
        csv = TMP / "tumble.csv"
        rows = ["t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz,wx,wy,wz,dwx,dwy,dwz,ax,ay,az"]
        for s in inertia_samples(count=200):
            k = s.kinematics
            values = [s.t, 0, 0, 0, s.orientation.w, s.orientation.x, s.orientation.y, s.orientation.z,
                      s.wrench.force.x, s.wrench.force.y, s.wrench.force.z,
                      s.wrench.torque.x, s.wrench.torque.y, s.wrench.torque.z,
                      k.angular_velocity.x, k.angular_velocity.y, k.angular_velocity.z,
                      k.angular_acceleration.x, k.angular_acceleration.y, k.angular_acceleration.z,
                      k.acceleration.x, k.acceleration.y, k.acceleration.z]
            rows.append(",".join(repr(float(v)) for v in values))
        csv.write_text("\n".join(rows) + "\n", encoding="utf-8")
        run = self.tool("tactforce-inertia-py", "--server", SERVER, "--csv", str(csv), "--method", "baseline-ls",
                        "--batch", "50", "--json")
        self.assertEqual(run.returncode, 0, run.stderr)
        response = json.loads(run.stdout)
        self.assertEqual(response["samples_received"], 200)
        self.assertAlmostEqual(response["mass"], MASS, delta=1e-3 * MASS)
        run = self.tool("tactforce-inertia-py", "--server", SERVER, "--csv", str(TMP / "missing.csv"))
        self.assertEqual(run.returncode, 2, run.stderr)


if __name__ == "__main__":
    unittest.main()
