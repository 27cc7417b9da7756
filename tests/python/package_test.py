"""The installed tactforce package against a live tactforce-server (run by
run_package_test.py with the venv's interpreter; TACTFORCE_TEST_SERVER is
the server's address). One call per RPC through tactforce.Client with a
sensible answer, the errors' exit codes (2 bad input, 3 unavailable,
4 deadline) and the command-line tools' exit codes; the friction and audit
CSV readers on data drawn from a seed; plan_friction_probe and the tool's
--friction-probe; the grpc.health.v1 stubs beside the real grpc package;
the two-space JSON of the tools."""

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
PROBE = SOURCE / "client" / "examples" / "friction_probe.json"
SEED = int(os.environ.get("TACTFORCE_TEST_SEED", "25"))


def indentation_errors(text):
    """Lines of `text` (pretty JSON) not indented two spaces per open
    bracket, as 'line N: ...'; [] when every line is."""
    errors, depth = [], 0
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.lstrip(" ")
        expected = depth - (1 if stripped[:1] in "}]" else 0)
        if len(line) - len(stripped) != 2 * expected:
            errors.append(f"line {number}: {len(line) - len(stripped)} spaces, expected {2 * expected}: {line!r}")
        in_string = escaped = False
        for c in stripped:
            if in_string:
                if escaped:
                    escaped = False
                elif c == "\\":
                    escaped = True
                elif c == '"':
                    in_string = False
            elif c == '"':
                in_string = True
            elif c in "{[":
                depth += 1
            elif c in "}]":
                depth -= 1
    return errors


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

    def test_plan_takes_the_fit_and_the_friction_estimate_directly(self):
        """Issue 28: FitInertia's and EstimateFriction's answers go into a plan unchanged."""
        from tactforce.plan import apply_estimates
        samples = inertia_samples()

        def requests():
            first = inertia_pb2.FitInertiaRequest()
            first.options.method = inertia_pb2.INERTIA_METHOD_BASELINE_LS
            yield first
            yield inertia_pb2.FitInertiaRequest(samples=samples)

        fit = self.client.FitInertia(requests())
        self.assertEqual(len(fit.covariance), 100)
        friction = self.client.EstimateFriction(friction_request(mu=0.5, trials=3))
        self.assertGreater(friction.mu_sigma, 0.0)
        from google.protobuf import json_format
        request = json_format.ParseDict(read_json(SPHERE_PINCH), planner_pb2.PlanRequest())
        apply_estimates(request, inertia=fit, friction=friction)
        self.assertEqual(list(request.object.uncertainty.covariance), list(fit.covariance))
        self.assertEqual(request.contacts[0].friction_sigma, friction.mu_sigma)
        response = self.client.Plan(request)
        self.assertGreater(len(response.row_margins), 0, response.message)

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


def write_friction_csv(path, trial, slip_column):
    """A FrictionTrial as the CSV `tactforce friction` reads."""
    header = "t,fx,fy,fz,px,py,pz" + (",slip" if slip_column else "")
    rows = [header]
    for s in trial.samples:
        values = [s.t, s.force.x, s.force.y, s.force.z, s.contact_point.x, s.contact_point.y, s.contact_point.z]
        row = ",".join(repr(v) for v in values)
        slipping = s.contact_point.x != 0.0 or s.contact_point.y != 0.0  # the probe has moved
        rows.append(row + (f",{int(slipping)}" if slip_column else ""))
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")


class CsvReadersTest(unittest.TestCase):
    """tactforce.friction and tactforce.audit on files drawn from SEED."""

    @classmethod
    def setUpClass(cls):
        cls.client = tactforce.Client(SERVER, timeout=30)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()

    def test_friction_csvs_round_trip_and_recover_mu(self):
        from tactforce import friction as friction_csv
        rng = random.Random(SEED)
        for case in range(3):
            mu = rng.uniform(0.3, 0.9)
            trials = rng.randint(2, 5)
            drawn = friction_request(mu=mu, trials=trials)
            paths = []
            for i, trial in enumerate(drawn.trials):
                path = TMP / f"friction_{case}_{i}.csv"
                write_friction_csv(path, trial, slip_column=(i % 2 == 1))
                paths.append(str(path))
            read = friction_csv.friction_request(paths, normal=(0.0, 0.0, -1.0))
            self.assertEqual(len(read.trials), trials)
            for i, (got, want) in enumerate(zip(read.trials, drawn.trials)):
                self.assertEqual(got.name, Path(paths[i]).name)
                self.assertEqual(len(got.samples), len(want.samples))
                self.assertEqual([s.t for s in got.samples], [s.t for s in want.samples])
                self.assertEqual([s.force.z for s in got.samples], [s.force.z for s in want.samples])
                self.assertEqual([s.contact_point.x for s in got.samples], [s.contact_point.x for s in want.samples])
                self.assertEqual(got.samples[0].HasField("slip"), i % 2 == 1)
                if i % 2 == 1:
                    self.assertEqual([s.slip for s in got.samples],
                                     [s.contact_point.x != 0 or s.contact_point.y != 0 for s in want.samples])
            response = self.client.EstimateFriction(read)
            self.assertEqual(response.count, trials)
            self.assertAlmostEqual(response.median, mu, delta=0.05 * mu, msg=f"case {case}: mu {mu}")

    def test_friction_csv_errors_name_file_line_and_column(self):
        from tactforce._csv import BadInput
        from tactforce.friction import read_trial
        bad = TMP / "bad_friction.csv"
        bad.write_text("t,fx,fy,fz,px,py,pz\n0,0,0,-1,0,0,0\n0.1,0,0,x,0,0,0\n", encoding="utf-8")
        with self.assertRaisesRegex(BadInput, r"bad_friction.csv:3: column 'fz': not a number"):
            read_trial(str(bad))
        bad.write_text("t,fx,fy,fz,px,py\n0,0,0,-1,0,0\n", encoding="utf-8")
        with self.assertRaisesRegex(BadInput, r"missing column\(s\) pz"):
            read_trial(str(bad))
        bad.write_text("t,fx,fy,fz,px,py,pz\n0.2,0,0,-1,0,0,0\n0.1,0,0,-1,0,0,0\n", encoding="utf-8")
        with self.assertRaisesRegex(BadInput, r":3: column 't': not increasing"):
            read_trial(str(bad))

    def test_audit_csv_skips_nan_rows_and_finds_the_deadzone(self):
        from tactforce.audit import audit_request, read_samples
        rng = random.Random(SEED + 1)
        threshold = rng.uniform(0.25, 0.6)
        drawn = audit_request_from(threshold, rng)
        path = TMP / "audit_run.csv"
        nan_rows = sorted(rng.sample(range(len(drawn.samples)), rng.randint(1, 12)))
        lines = ["t,reference,reading,trial"]
        for k, sample in enumerate(drawn.samples):
            reading = "nan" if k in nan_rows[::2] else ("" if k in nan_rows[1::2] else repr(sample.reading))
            lines.append(f"{sample.t!r},{sample.reference!r},{reading},3")
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
        samples, skipped = read_samples(str(path))
        self.assertEqual(skipped, len(nan_rows))
        self.assertEqual(len(samples), len(drawn.samples) - len(nan_rows))
        kept = [s for k, s in enumerate(drawn.samples) if k not in nan_rows]
        self.assertEqual([s.reading for s in samples], [s.reading for s in kept])
        self.assertTrue(all(s.trial == 3 for s in samples))
        request = audit_request(str(path), reading_units="N")
        self.assertEqual(request.source, "audit_run.csv")
        response = self.client.AuditModel(request)
        self.assertEqual(response.causes[0].effect, "deadzone", response.summary)
        self.assertAlmostEqual(response.causes[0].parameters["threshold"], threshold, delta=0.05)

    def test_audit_csv_errors(self):
        from tactforce._csv import BadInput
        from tactforce.audit import read_samples
        bad = TMP / "bad_audit.csv"
        bad.write_text("t,reference\n0,1\n", encoding="utf-8")
        with self.assertRaisesRegex(BadInput, r"missing column\(s\) reading"):
            read_samples(str(bad))
        bad.write_text("t,reference,reading,trial\n0,1,2,0.5\n", encoding="utf-8")
        with self.assertRaisesRegex(BadInput, r"bad_audit.csv:2: column 'trial': not an integer"):
            read_samples(str(bad))


    def test_audit_taxel_csv_names_the_silent_taxels(self):
        from tactforce.audit import audit_request, read_samples
        rng = random.Random(SEED + 2)
        n_taxels = rng.randint(6, 12)
        dead = sorted(rng.sample(range(n_taxels), rng.randint(1, 3)))
        path = TMP / "audit_taxels.csv"
        write_taxel_csv(path, n_taxels, dead, rng)
        samples, skipped = read_samples(str(path))
        self.assertEqual(skipped, 0)
        self.assertTrue(all(len(s.taxels) == n_taxels for s in samples))
        # No reading column: the reading is the taxels' sum (the fingertip force).
        self.assertTrue(all(math.isclose(s.reading, math.fsum(s.taxels)) for s in samples))
        request = audit_request(str(path), reading_units="N", taxels=n_taxels, blocks=0)
        self.assertTrue(request.HasField("blocks"))
        self.assertEqual(request.blocks, 0)
        response = self.client.AuditModel(request)
        self.assertEqual(response.causes[0].effect, "partial_activation", response.summary)
        self.assertEqual(response.causes[0].found_by, "taxels")
        self.assertEqual(response.causes[0].parameters["silent_taxels"], len(dead), response.summary)
        self.assertAlmostEqual(response.causes[0].parameters["fraction"], len(dead) / n_taxels)

    def test_audit_taxel_csv_errors(self):
        from tactforce._csv import BadInput
        from tactforce.audit import audit_request, read_samples
        bad = TMP / "bad_taxels.csv"
        bad.write_text("t,reference,taxel_0,taxel_2\n0,1,2,3\n", encoding="utf-8")
        with self.assertRaisesRegex(BadInput, r"bad_taxels.csv: missing column\(s\) taxel_1 "
                                              r"\(per-taxel data needs taxel_0 ... taxel_2\)"):
            read_samples(str(bad))
        with self.assertRaisesRegex(BadInput, r"missing column\(s\) taxel_1, taxel_3, taxel_4"):
            read_samples(str(bad), taxels=5)
        with self.assertRaisesRegex(BadInput, r"column 'taxel_2' beyond the 2 taxels expected"):
            read_samples(str(bad), taxels=2)
        with self.assertRaisesRegex(BadInput, r"taxels: must be in \[1, 4096\], got 0"):
            read_samples(str(bad), taxels=0)
        bad.write_text("t,reference,taxel_0,taxel_1\n0,1,2,3\n0.1,1,x,3\n", encoding="utf-8")
        with self.assertRaisesRegex(BadInput, r"bad_taxels.csv:3: column 'taxel_0': not a number"):
            read_samples(str(bad))
        bad.write_text("t,reference\n0,1\n", encoding="utf-8")
        with self.assertRaisesRegex(BadInput, r"missing column\(s\) reading \(or per-taxel columns"):
            read_samples(str(bad))
        bad.write_text("t,reference,taxel_0\n0,1,2\n", encoding="utf-8")
        with self.assertRaisesRegex(BadInput, r"blocks: must be in \[0, 10\], got 11"):
            audit_request(str(bad), blocks=11)

def write_taxel_csv(path, n_taxels, dead, rng, rate=100.0):
    """A calibration sweep of `n_taxels` taxels: each pressed once in random
    order (0.3 s ramp up, 0.1 s hold, 0.3 s down, 0.2 s rest, peak 2-5 N),
    the pressed taxel taking 70 % of the load and its neighbours 15 % each;
    every taxel with its own noise (0.005-0.02 N); the `dead` ones read
    noise only. No reading column (the audit sums the taxels)."""
    order = list(range(n_taxels))
    rng.shuffle(order)
    noise = [rng.uniform(0.005, 0.02) for _ in range(n_taxels)]
    rows = ["t,reference," + ",".join(f"taxel_{j}" for j in range(n_taxels))]
    k = 0
    for pressed in order:
        peak = rng.uniform(2.0, 5.0)
        for step in range(int(0.9 * rate)):
            u = step / rate
            force = peak * min(1.0, u / 0.3, max(0.0, (0.7 - u) / 0.3))
            share = [0.0] * n_taxels
            share[pressed] = 0.7
            share[(pressed - 1) % n_taxels] += 0.15
            share[(pressed + 1) % n_taxels] += 0.15
            taxels = [(0.0 if j in dead else force * share[j]) + rng.gauss(0.0, noise[j])
                      for j in range(n_taxels)]
            rows.append(f"{k / rate!r},{force!r}," + ",".join(repr(v) for v in taxels))
            k += 1
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")


def audit_request_from(threshold, rng, seconds=15.0, rate=50.0):
    """audit_request's deadzone sensor with a drawn threshold and noise."""
    request = audit_pb2.AuditRequest(source="drawn")
    noise = rng.uniform(0.005, 0.02)
    for k in range(int(seconds * rate)):
        t = k / rate
        phase = (t % 3.0) / 3.0
        reference = 4.0 * (2 * phase if phase < 0.5 else 2 - 2 * phase)
        request.samples.add(t=t, reference=reference,
                            reading=max(0.0, reference - threshold) + rng.gauss(0.0, noise))
    return request


class FrictionProbeTest(unittest.TestCase):
    """Client.plan_friction_probe over the test's server (an ephemeral port)."""

    @classmethod
    def setUpClass(cls):
        cls.client = tactforce.Client(SERVER, timeout=30)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()

    def test_plan_friction_probe_follows_the_drawn_ramp(self):
        rng = random.Random(SEED + 2)
        for case in range(4):
            initial = rng.uniform(1.5, 3.0)
            final = rng.uniform(0.5, initial - 0.2)
            ramp, rate, tangential = rng.uniform(0.5, 2.0), rng.uniform(5.0, 20.0), rng.uniform(0.1, 0.6)
            response = self.client.plan_friction_probe(
                wrench_grasp(), position=(0.0, 0.0, 0.012), normal=(0.0, 0.0, -1.0), tangent=(1.0, 0.0, 0.0),
                tangential_force=tangential, initial_normal_force=initial, final_normal_force=final,
                ramp_rate=ramp, sample_rate=rate)
            count = math.floor((initial - final) / ramp * rate) + 1
            self.assertEqual(len(response.times), count, f"case {case}")
            self.assertEqual(len(response.holding.steps), count)
            for t, force in zip(response.times, response.probe_forces):
                self.assertAlmostEqual(-force.z, max(final, initial - ramp * t), delta=1e-9)
                self.assertAlmostEqual(force.x, tangential, delta=1e-12)
            # The same request as a message: the same answer.
            request = planner_pb2.FrictionProbeRequest(
                tangential_force=tangential, initial_normal_force=initial, final_normal_force=final,
                ramp_rate=ramp, sample_rate=rate)
            request.plan.CopyFrom(wrench_grasp())
            set_vec(request.position, [0.0, 0.0, 0.012])
            set_vec(request.normal, [0.0, 0.0, -1.0])
            set_vec(request.tangent, [1.0, 0.0, 0.0])
            direct = self.client.PlanFrictionProbe(request)
            self.assertEqual([f.z for f in direct.probe_forces], [f.z for f in response.probe_forces])
            self.assertEqual([s.status for s in direct.holding.steps], [s.status for s in response.holding.steps])

    def test_plan_friction_probe_bad_input_is_exit_code_2(self):
        with self.assertRaises(tactforce.TactforceError) as caught:
            self.client.plan_friction_probe(wrench_grasp(), position=(0, 0), normal=(0, 0, -1), tangent=(1, 0, 0),
                                            tangential_force=0.5, initial_normal_force=2, final_normal_force=1,
                                            ramp_rate=1, sample_rate=10)
        self.assertEqual(caught.exception.exit_code, 2)
        self.assertIn("position", caught.exception.details)
        with self.assertRaises(tactforce.TactforceError) as caught:
            self.client.plan_friction_probe(wrench_grasp(), position=(0, 0, 0.012), normal=(0, 0, -1),
                                            tangent=(1, 0, 0), tangential_force=0.5, initial_normal_force=2,
                                            final_normal_force=1, ramp_rate=0, sample_rate=10)
        self.assertEqual(caught.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("ramp_rate", caught.exception.details)


class HealthStubsTest(unittest.TestCase):
    """The grpc.health.v1 stubs live in tactforce.health.v1: importable
    beside the real grpc package, which they do not shadow."""

    def test_health_stubs_import_beside_the_real_grpc(self):
        from tactforce.health.v1 import health_pb2, health_pb2_grpc
        self.assertTrue(hasattr(grpc, "insecure_channel"), grpc.__file__)
        self.assertFalse(Path(grpc.__file__).resolve().is_relative_to(Path(tactforce.__file__).parent.resolve()))
        self.assertEqual(health_pb2.DESCRIPTOR.package, "grpc.health.v1")
        self.assertTrue(hasattr(health_pb2_grpc, "HealthStub"))
        # Nothing the install added is a top-level grpc folder.
        site = Path(tactforce.__file__).resolve().parent.parent
        self.assertFalse((site / "grpc" / "health").exists(), site)
        # A fresh interpreter imports both, in either order.
        for order in ("import grpc; import tactforce.health.v1.health_pb2_grpc as h",
                      "import tactforce.health.v1.health_pb2_grpc as h; import grpc"):
            run = subprocess.run([str(VENV / "bin" / "python"), "-c", order + "; grpc.insecure_channel; h.HealthStub"],
                                 capture_output=True, text=True, timeout=60)
            self.assertEqual(run.returncode, 0, run.stderr)

    def test_check_health_over_the_standard_service(self):
        with tactforce.Client(SERVER, timeout=30) as client:
            self.assertEqual(client.CheckHealth(), "SERVING")
            self.assertEqual(client.CheckHealth("tactforce.v1.Planner"), "SERVING")
            with self.assertRaises(tactforce.TactforceError) as caught:
                client.CheckHealth("no.such.Service")
        self.assertEqual(caught.exception.code, grpc.StatusCode.NOT_FOUND)


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

    def test_plan_tool_friction_probe(self):
        run = self.tool("tactforce-plan-py", "--server", SERVER, "--friction-probe", str(PROBE), "--json")
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertEqual(indentation_errors(run.stdout), [])
        response = json.loads(run.stdout)
        request = read_json(PROBE)
        count = math.floor((request["initial_normal_force"] - request["final_normal_force"])
                           / request["ramp_rate"] * request["sample_rate"]) + 1
        self.assertEqual(len(response["times"]), count)
        self.assertEqual(len(response["holding"]["steps"]), count)
        run = self.tool("tactforce-plan-py", "--server", SERVER, "--friction-probe", str(PROBE))
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertIn(f"{count} samples: {count} optimal", run.stdout)
        run = self.tool("tactforce-plan-py", "--server", SERVER, "--friction-probe", str(TMP / "missing.json"))
        self.assertEqual(run.returncode, 2, run.stderr)
        run = self.tool("tactforce-plan-py", "--server", SERVER, "--friction-probe", str(PROBE),
                        "--request", str(SPHERE_PINCH))
        self.assertEqual(run.returncode, 2, run.stderr)
        self.assertIn("--friction-probe", run.stderr)

    def test_tools_print_two_space_json(self):
        for args in (("tactforce-plan-py", "--request", str(SPHERE_PINCH)),
                     ("tactforce-plan-py", "--request", str(SPHERE_PINCH), "--stream")):
            run = self.tool(args[0], "--server", SERVER, *args[1:], "--json")
            self.assertEqual(run.returncode, 0, run.stderr)
            self.assertEqual(indentation_errors(run.stdout), [], args)
            self.assertIn('\n  "status": ', run.stdout)

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
        self.assertEqual(indentation_errors(run.stdout), [])
        response = json.loads(run.stdout)
        self.assertEqual(response["samples_received"], 200)
        self.assertAlmostEqual(response["mass"], MASS, delta=1e-3 * MASS)
        run = self.tool("tactforce-inertia-py", "--server", SERVER, "--csv", str(TMP / "missing.csv"))
        self.assertEqual(run.returncode, 2, run.stderr)


if __name__ == "__main__":
    unittest.main()
