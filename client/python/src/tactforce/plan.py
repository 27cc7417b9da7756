"""Plan fingertip contact forces on a running tactforce-server.

Sends one PlanRequest (the built-in 3-finger wrench grasp, or a PlanRequest
JSON file) to tactforce.v1.Planner and prints the force of every contact;
or, with --friction-probe FILE, a FrictionProbeRequest to PlanFrictionProbe
and prints the probe's force and the holding plan per sample.

    tactforce-plan-py --server 127.0.0.1:50051
    python3 -m tactforce.plan --server 127.0.0.1:50051 \\
        --request client/examples/sphere_pinch.json --solver ipopt --json
    tactforce-plan-py --server 127.0.0.1:50051 --friction-probe client/examples/friction_probe.json

Exit codes (those of the `tactforce` CLI): 0 an answer was computed
(optimal, infeasible or solver failure: see the status line), 1 any other
failure, 2 bad command line, unreadable file or invalid request
(INVALID_ARGUMENT), 3 server unreachable (UNAVAILABLE), 4 deadline exceeded.
"""

from __future__ import annotations

import argparse
import sys
from typing import List, Optional, TextIO

from google.protobuf import json_format
from google.protobuf.message import Message

from tactforce._cli import print_json, report, wire_choices
from tactforce.client import Client, tls_credentials
from tactforce.errors import EXIT_BAD_INPUT, EXIT_FAILURE, EXIT_OK, TactforceError
from tactforce.v1 import estimator_pb2, inertia_pb2, planner_pb2

SOLVERS = wire_choices(planner_pb2.Solver, "SOLVER_")


def wrench_grasp() -> planner_pb2.PlanRequest:
    """3-finger grasp of a 0.3 kg wrench handle (the planner's 'wrench-3f').

    Handle along x, 24 mm wide, centre of mass 1 cm towards the head;
    mu 0.9, reading sigma 0.5 N, minimum normal force 0.3 N per finger.
    """
    request = planner_pb2.PlanRequest()
    request.object.mass = 0.3
    request.object.com.x = 0.01
    half_width = 0.012
    fingers = [
        ("index", (0.02, half_width, 0.0), (0.0, -1.0, 0.0)),
        ("middle", (-0.02, half_width, 0.0), (0.0, -1.0, 0.0)),
        ("thumb", (0.0, -half_width, 0.0), (0.0, 1.0, 0.0)),
    ]
    for name, position, normal in fingers:
        contact = request.contacts.add()
        contact.name = name
        contact.position.x, contact.position.y, contact.position.z = position
        contact.normal.x, contact.normal.y, contact.normal.z = normal
        contact.friction = 0.9
        contact.kind = planner_pb2.CONTACT_KIND_INTRINSIC
        contact.sigma = 0.5
        contact.min_normal_force = 0.3
    request.solver = planner_pb2.SOLVER_GEOMETRIC
    return request


def apply_estimates(request: planner_pb2.PlanRequest,
                    inertia: Optional[Message] = None,
                    friction: Optional[Message] = None) -> planner_pb2.PlanRequest:
    """Fill `request` from earlier estimates, with their uncertainty (in place).

    `inertia`: a FitInertiaResponse (Client.FitInertia's answer): mass, CoM,
    inertia, and its `covariance` as object.uncertainty.covariance unchanged.
    `friction`: a FrictionResponse (Client.EstimateFriction's answer): every
    fingertip (non-EXTRINSIC) contact's friction = median, friction_sigma =
    mu_sigma. As `tactforce plan --inertia FIT.json --friction FRICTION.json`.
    """
    if inertia is not None:
        if not inertia.mass > 0:
            raise ValueError(f"inertia: the fit has no positive mass ({inertia.mass} kg)")
        if len(inertia.covariance) not in (0, 100):
            raise ValueError(f"inertia: covariance has {len(inertia.covariance)} entries, need 100")
        obj = request.object
        obj.mass = inertia.mass
        obj.com.CopyFrom(inertia.com)
        obj.inertia.CopyFrom(inertia.inertia)
        del obj.uncertainty.covariance[:]
        del obj.uncertainty.com_covariance[:]
        obj.uncertainty.mass_sigma = 0.0
        obj.uncertainty.covariance.extend(inertia.covariance)
    if friction is not None:
        if friction.count <= 0:
            raise ValueError("friction: no trial slipped (count 0): no friction estimate")
        for contact in request.contacts:
            if contact.kind != planner_pb2.CONTACT_KIND_EXTRINSIC:
                contact.friction = friction.median
                contact.friction_sigma = friction.mu_sigma
    return request


def load_request(path: str, message_type: type = planner_pb2.PlanRequest) -> Message:
    """A PlanRequest (or `message_type`) JSON file ('-' = stdin)."""
    if path == "-":
        text = sys.stdin.read()
    else:
        with open(path, encoding="utf-8") as handle:
            text = handle.read()
    return json_format.Parse(text, message_type())


def status_name(value: int) -> str:
    return planner_pb2.PlanStatus.Name(value).removeprefix("PLAN_STATUS_")


def solver_name(value: int) -> str:
    return planner_pb2.Solver.Name(value).removeprefix("SOLVER_")


def print_table(request: planner_pb2.PlanRequest, response: planner_pb2.PlanResponse, out: TextIO) -> None:
    print(f"status: {status_name(response.status)}"
          f"  solver: {solver_name(response.solver)}"
          f"  time: {response.solve_time_us} us"
          f"  iterations: {response.iterations}", file=out)
    if response.message:
        print(f"message: {response.message}", file=out)
    if response.forces:
        print(f"{'contact':<10} {'fx [N]':>11} {'fy [N]':>11} {'fz [N]':>11}"
              f" {'fn [N]':>11} {'sigma [N]':>10}", file=out)
        for i, force in enumerate(response.forces):
            name = request.contacts[i].name if i < len(request.contacts) else ""
            normal = response.normal_forces[i] if i < len(response.normal_forces) else 0.0
            sigma = (response.normal_force_sigma[i]
                     if i < len(response.normal_force_sigma) else 0.0)
            print(f"{name or str(i):<10} {force.x:11.6f} {force.y:11.6f} {force.z:11.6f}"
                  f" {normal:11.6f} {sigma:10.6f}", file=out)
        print(f"objective: {response.objective:.6g} N^2"
              f"  min margin: {response.min_margin:.6g} N", file=out)
    if response.solver == planner_pb2.SOLVER_CROSS_CHECK:
        check = response.cross_check
        print(f"cross-check: {'agree' if check.agree else 'DISAGREE'}"
              f"  max |df| {check.max_force_diff:.3g} N"
              f"  ipopt {status_name(check.ipopt_status)} in {check.ipopt_time_us} us",
              file=out)


def print_probe_table(response: planner_pb2.FrictionProbeResponse, out: TextIO) -> None:
    """One line per probe sample, as `tactforce plan --friction-probe`."""
    print(f"{'step':>5}  {'t (s)':>8}  {'probe force (N)':<26}  {'holding':<14}  holding normal forces (N)", file=out)
    for k, t in enumerate(response.times):
        f = response.probe_forces[k]
        step = response.holding.steps[k] if k < len(response.holding.steps) else planner_pb2.PlanResponse()
        normals = " ".join(f"{fn:7.3f}" for fn in step.normal_forces)
        print(f"{k:5d}  {t:8.3f}  {f.x:8.3f} {f.y:8.3f} {f.z:8.3f}  {status_name(step.status):<14}  {normals}",
              file=out)
    h = response.holding
    print(f"{len(response.times)} samples: {h.optimal_steps} optimal, {h.infeasible_steps} infeasible, "
          f"{h.failed_steps} failed; total {h.total_time_us} us", file=out)


def parse_args(argv: Optional[List[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="tactforce-plan-py",
        description="Plan contact forces on a tactforce-server and print them.")
    parser.add_argument("--server", default="127.0.0.1:50051",
                        help="host:port of tactforce-server (default %(default)s)")
    parser.add_argument("--request", metavar="FILE",
                        help="PlanRequest JSON ('-' = stdin); default: the built-in "
                             "3-finger wrench grasp")
    parser.add_argument("--friction-probe", metavar="FILE",
                        help="FrictionProbeRequest JSON ('-' = stdin) instead of --request: the probe's "
                             "force and the holding plan per sample (Planner.PlanFrictionProbe)")
    parser.add_argument("--inertia", metavar="FIT.json",
                        help="FitInertiaResponse JSON: object mass, CoM, inertia and their covariance")
    parser.add_argument("--friction", metavar="FRICTION.json",
                        help="FrictionResponse JSON: fingertip friction = median, friction_sigma = mu_sigma")
    parser.add_argument("--solver", choices=sorted(SOLVERS),
                        help="override the request's solver")
    parser.add_argument("--timeout", type=float, default=10.0,
                        help="RPC deadline in seconds (default %(default)s)")
    parser.add_argument("--stream", action="store_true",
                        help="send the request over PlanStream instead of Plan")
    parser.add_argument("--json", action="store_true",
                        help="print the PlanResponse as JSON instead of a table")
    parser.add_argument("--tls-ca", metavar="PEM", help="CA that signed the server certificate")
    parser.add_argument("--tls-cert", metavar="PEM", help="client certificate (mutual TLS)")
    parser.add_argument("--tls-key", metavar="PEM", help="client private key (mutual TLS)")
    parser.add_argument("--tls-server-name", metavar="NAME",
                        help="expected server name in its certificate, if not the host")
    args = parser.parse_args(argv)
    if args.friction_probe and (args.request or args.stream):
        parser.error("--friction-probe excludes --request and --stream")
    return args


def connect(args: argparse.Namespace) -> Client:
    credentials = None
    if args.tls_ca or args.tls_cert or args.tls_key:
        credentials = tls_credentials(args.tls_ca, args.tls_cert, args.tls_key)
    return Client(args.server, timeout=args.timeout, credentials=credentials,
                  server_name=args.tls_server_name)


def run_friction_probe(args: argparse.Namespace) -> int:
    """--friction-probe: Planner.PlanFrictionProbe; printed as the CLI does."""
    try:
        request = load_request(args.friction_probe, planner_pb2.FrictionProbeRequest)
    except (OSError, json_format.ParseError) as error:
        print(f"error: {args.friction_probe}: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.solver:
        request.plan.solver = SOLVERS[args.solver]
    try:
        with connect(args) as client:
            response = client.PlanFrictionProbe(request)
    except OSError as error:
        print(f"error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except TactforceError as error:
        return report(error)
    if args.json:
        print_json(response)
    else:
        print_probe_table(response, sys.stdout)
    return EXIT_OK


def main(argv: Optional[List[str]] = None) -> int:
    args = parse_args(argv)
    if args.friction_probe:
        return run_friction_probe(args)
    try:
        request = load_request(args.request) if args.request else wrench_grasp()
    except (OSError, json_format.ParseError) as error:
        print(f"error: {args.request}: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        fit = load_request(args.inertia, inertia_pb2.FitInertiaResponse) if args.inertia else None
        mu = load_request(args.friction, estimator_pb2.FrictionResponse) if args.friction else None
        apply_estimates(request, fit, mu)
    except (OSError, json_format.ParseError, ValueError) as error:
        print(f"error: --inertia/--friction: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.solver:
        request.solver = SOLVERS[args.solver]

    try:
        with connect(args) as client:
            if args.stream:
                responses = list(client.PlanStream([request]))
                if len(responses) != 1:
                    print(f"error: PlanStream returned {len(responses)} responses for 1 request",
                          file=sys.stderr)
                    return EXIT_FAILURE
                response = responses[0]
            else:
                response = client.Plan(request)
    except OSError as error:
        print(f"error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except TactforceError as error:
        return report(error)

    if args.json:
        print_json(response)
    else:
        print_table(request, response, sys.stdout)
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
