"""tactforce.Client: one typed method per RPC of the tactforce.v1 services.

    import tactforce
    from tactforce.v1 import planner_pb2

    with tactforce.Client("127.0.0.1:50051", timeout=10) as client:
        response = client.Plan({"object": {"mass": 0.1}, "contacts": [...]})
        print(planner_pb2.PlanStatus.Name(response.status), response.forces)

Requests are the generated messages (tactforce.v1.*_pb2) or dicts in the
proto JSON mapping (what the CLI's --request files hold). Every failed call
raises tactforce.TactforceError with the gRPC status code and the exit code
the `tactforce` CLI would use (2 bad input, 3 unavailable, 4 deadline, 1
anything else).
"""

from __future__ import annotations

from typing import Any, Callable, Iterable, Iterator, Mapping, Optional, Sequence, Tuple, Type, TypeVar, Union

import grpc
from google.protobuf import json_format, symbol_database
from google.protobuf.message import Message

from tactforce.errors import TactforceError
from tactforce.health.v1 import health_pb2, health_pb2_grpc
from tactforce.v1 import (audit_pb2, audit_pb2_grpc, estimator_pb2, estimator_pb2_grpc, inertia_pb2,
                          planner_pb2, planner_pb2_grpc)

try:  # tactforce.v1.Info exists when proto/tactforce/v1/info.proto did at build time.
    from tactforce.v1 import info_pb2, info_pb2_grpc
except ImportError:  # pragma: no cover - depends on the protos built
    info_pb2 = info_pb2_grpc = None

#: True when the package was built with the tactforce.v1.Info service
#: (Client.GetServerInfo works; otherwise it raises UNIMPLEMENTED).
HAS_SERVER_INFO: bool = info_pb2_grpc is not None

M = TypeVar("M", bound=Message)
Request = Union[M, Mapping[str, Any]]


def _message(request: Any, message_type: Type[M], method: str) -> M:
    """`request` as a `message_type`: the message itself, or a dict in the
    proto JSON mapping (a bad dict is INVALID_ARGUMENT, exit code 2)."""
    if isinstance(request, message_type):
        return request
    if isinstance(request, Mapping):
        try:
            return json_format.ParseDict(request, message_type())
        except json_format.ParseError as error:
            raise TactforceError(grpc.StatusCode.INVALID_ARGUMENT,
                                 f"{message_type.DESCRIPTOR.name}: {error}", method) from None
    raise TypeError(f"{method}: expected {message_type.DESCRIPTOR.full_name} or a dict, "
                    f"got {type(request).__name__}")


class _Requests:
    """The caller's request stream, converted message by message. Keeps the
    first exception the caller's iterable raised: gRPC reports only
    "Exception iterating requests!", the client re-raises this one."""

    def __init__(self, requests: Iterable[Any], message_type: Type[Message], method: str) -> None:
        self._requests = iter(requests)
        self._type, self._method = message_type, method
        self.error: Optional[BaseException] = None

    def __iter__(self) -> "_Requests":
        return self

    def __next__(self) -> Message:
        try:
            return _message(next(self._requests), self._type, self._method)
        except StopIteration:
            raise
        except BaseException as error:
            self.error = error
            raise

    def failure(self, error: grpc.RpcError) -> BaseException:
        """What to raise for `error`: the stream's own exception if it had one."""
        if self.error is not None:
            return self.error
        return TactforceError.from_rpc_error(error, self._method)


def tls_credentials(ca: Optional[str] = None, cert: Optional[str] = None,
                    key: Optional[str] = None) -> grpc.ChannelCredentials:
    """TLS channel credentials from PEM files: the CA that signed the server
    certificate (None: the system roots) and, for mutual TLS, the client
    certificate and key. An unreadable file raises OSError."""

    def read(path: Optional[str]) -> Optional[bytes]:
        if not path:
            return None
        with open(path, "rb") as handle:
            return handle.read()

    return grpc.ssl_channel_credentials(root_certificates=read(ca), private_key=read(key),
                                        certificate_chain=read(cert))


class Client:
    """A connection to tactforce-server and one method per RPC.

    Args:
        target: "host:port" of tactforce-server.
        timeout: default deadline of every call in seconds (None: none);
            each method takes its own `timeout` too.
        credentials: TLS credentials (see :func:`tls_credentials`); None is
            plaintext.
        server_name: the name expected in the server certificate when it is
            not the host of `target`.
        options: extra gRPC channel options.
        channel: use this channel instead of opening one (the client then
            does not close it).
    """

    def __init__(self, target: str, timeout: Optional[float] = 30.0, *,
                 credentials: Optional[grpc.ChannelCredentials] = None,
                 server_name: Optional[str] = None,
                 options: Sequence[Tuple[str, Any]] = (),
                 channel: Optional[grpc.Channel] = None) -> None:
        self.target = target
        self.timeout = timeout
        self._owns_channel = channel is None
        if channel is None:
            options = list(options)
            if server_name:
                options.append(("grpc.ssl_target_name_override", server_name))
            if credentials is None:
                channel = grpc.insecure_channel(target, options=options)
            else:
                channel = grpc.secure_channel(target, credentials, options=options)
        self.channel: grpc.Channel = channel
        self._planner = planner_pb2_grpc.PlannerStub(channel)
        self._estimator = estimator_pb2_grpc.EstimatorStub(channel)
        self._audit = audit_pb2_grpc.AuditStub(channel)
        self._info = info_pb2_grpc.InfoStub(channel) if HAS_SERVER_INFO else None
        self._health = health_pb2_grpc.HealthStub(channel)

    def close(self) -> None:
        """Closes the channel (if the client opened it)."""
        if self._owns_channel:
            self.channel.close()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def _deadline(self, timeout: Optional[float]) -> Optional[float]:
        return self.timeout if timeout is None else timeout

    def _unary(self, rpc: Callable[..., Any], method: str, request: Message,
               timeout: Optional[float]) -> Any:
        try:
            return rpc(request, timeout=self._deadline(timeout))
        except grpc.RpcError as error:
            raise TactforceError.from_rpc_error(error, method) from error

    # tactforce.v1.Planner

    def Plan(self, request: Request[planner_pb2.PlanRequest], *,
             timeout: Optional[float] = None) -> planner_pb2.PlanResponse:
        """Contact forces for one grasp (Planner.Plan). An infeasible grasp is
        an answer (status PLAN_STATUS_INFEASIBLE), not an error."""
        return self._unary(self._planner.Plan, "Plan",
                           _message(request, planner_pb2.PlanRequest, "Plan"), timeout)

    def PlanStream(self, requests: Iterable[Request[planner_pb2.PlanRequest]], *,
                   timeout: Optional[float] = None) -> Iterator[planner_pb2.PlanResponse]:
        """One PlanResponse per PlanRequest, in order, over one stream
        (Planner.PlanStream). `timeout` bounds the whole stream. Errors are
        raised while iterating the responses."""
        stream = _Requests(requests, planner_pb2.PlanRequest, "PlanStream")
        call = self._planner.PlanStream(stream, timeout=self._deadline(timeout))
        return _responses(call, stream)

    def PlanTrajectory(self, request: Request[planner_pb2.TrajectoryRequest], *,
                       timeout: Optional[float] = None) -> planner_pb2.TrajectoryResponse:
        """One plan per step of a motion (Planner.PlanTrajectory)."""
        return self._unary(self._planner.PlanTrajectory, "PlanTrajectory",
                           _message(request, planner_pb2.TrajectoryRequest, "PlanTrajectory"), timeout)

    def PlanFrictionProbe(self, request: Request[planner_pb2.FrictionProbeRequest], *,
                          timeout: Optional[float] = None) -> planner_pb2.FrictionProbeResponse:
        """A friction probe's force ramp and the holding grasp per sample
        (Planner.PlanFrictionProbe)."""
        return self._unary(self._planner.PlanFrictionProbe, "PlanFrictionProbe",
                           _message(request, planner_pb2.FrictionProbeRequest, "PlanFrictionProbe"), timeout)

    def plan_friction_probe(self, plan: Request[planner_pb2.PlanRequest], *,
                            position: Sequence[float], normal: Sequence[float], tangent: Sequence[float],
                            tangential_force: float, initial_normal_force: float, final_normal_force: float,
                            ramp_rate: float, sample_rate: float,
                            timeout: Optional[float] = None) -> planner_pb2.FrictionProbeResponse:
        """PlanFrictionProbe from keyword arguments: `plan` the holding
        grasp; the probe at `position` (m, object frame) pressing along
        `normal` (into the object) with `tangential_force` (N) along
        `tangent`, its normal force ramped from `initial_normal_force` to
        `final_normal_force` (N) at `ramp_rate` (N/s), sampled at
        `sample_rate` (Hz). Returns the probe force and the holding plan per
        sample (response.times, .probe_forces, .holding.steps)."""
        request = planner_pb2.FrictionProbeRequest(
            tangential_force=tangential_force, initial_normal_force=initial_normal_force,
            final_normal_force=final_normal_force, ramp_rate=ramp_rate, sample_rate=sample_rate)
        request.plan.CopyFrom(_message(plan, planner_pb2.PlanRequest, "PlanFrictionProbe"))
        for field, values in (("position", position), ("normal", normal), ("tangent", tangent)):
            if len(values) != 3:
                raise TactforceError(grpc.StatusCode.INVALID_ARGUMENT,
                                     f"{field}: expected 3 numbers, got {len(values)}", "PlanFrictionProbe")
            vec = getattr(request, field)
            vec.x, vec.y, vec.z = (float(v) for v in values)
        return self.PlanFrictionProbe(request, timeout=timeout)

    # tactforce.v1.Estimator

    def EstimateForces(self, request: Request[estimator_pb2.EstimateRequest], *,
                       timeout: Optional[float] = None) -> estimator_pb2.EstimateResponse:
        """Contact forces from tactile normal-force readings
        (Estimator.EstimateForces): one force per contact."""
        return self._unary(self._estimator.EstimateForces, "EstimateForces",
                           _message(request, estimator_pb2.EstimateRequest, "EstimateForces"), timeout)

    def EstimateFriction(self, request: Request[estimator_pb2.FrictionRequest], *,
                         timeout: Optional[float] = None) -> estimator_pb2.FrictionResponse:
        """Friction coefficients from slip trials (Estimator.EstimateFriction)."""
        return self._unary(self._estimator.EstimateFriction, "EstimateFriction",
                           _message(request, estimator_pb2.FrictionRequest, "EstimateFriction"), timeout)

    def FitInertia(self, requests: Iterable[Request[inertia_pb2.FitInertiaRequest]], *,
                   timeout: Optional[float] = None) -> inertia_pb2.FitInertiaResponse:
        """Mass, centre of mass and inertia from a client stream
        (Estimator.FitInertia): the first message carries the options, every
        message a batch of samples. An exception raised by `requests` itself
        (e.g. a bad CSV row) is re-raised as it is."""
        stream = _Requests(requests, inertia_pb2.FitInertiaRequest, "FitInertia")
        try:
            return self._estimator.FitInertia(stream, timeout=self._deadline(timeout))
        except grpc.RpcError as error:
            raise stream.failure(error) from error

    # tactforce.v1.Audit

    def AuditModel(self, request: Request[audit_pb2.AuditRequest], *,
                   timeout: Optional[float] = None) -> audit_pb2.AuditResponse:
        """Sensor-model audit of measured reference/reading samples
        (Audit.AuditModel)."""
        return self._unary(self._audit.AuditModel, "AuditModel",
                           _message(request, audit_pb2.AuditRequest, "AuditModel"), timeout)

    # grpc.health.v1.Health (tactforce.health.v1)

    def CheckHealth(self, service: str = "", *, timeout: Optional[float] = None) -> str:
        """The server's health (grpc.health.v1.Health/Check) for `service`
        ("" = the whole server, or e.g. "tactforce.v1.Planner") by its name
        in health.proto: "SERVING", "NOT_SERVING", ... An unknown service is
        TactforceError(NOT_FOUND)."""
        response = self._unary(self._health.Check, "Check",
                               health_pb2.HealthCheckRequest(service=service), timeout)
        return health_pb2.HealthCheckResponse.ServingStatus.Name(response.status)

    # tactforce.v1.Info (only when the package was built with info.proto)

    def GetServerInfo(self, request: Optional[Request[Message]] = None, *,
                      timeout: Optional[float] = None) -> Message:
        """The server's version and build (Info.GetServerInfo). Raises
        TactforceError(UNIMPLEMENTED) when this package was built without
        info.proto (see HAS_SERVER_INFO) or the server lacks the service."""
        if not HAS_SERVER_INFO:
            raise TactforceError(grpc.StatusCode.UNIMPLEMENTED,
                                 "this tactforce package was built without tactforce/v1/info.proto",
                                 "GetServerInfo")
        rpc = info_pb2.DESCRIPTOR.services_by_name["Info"].methods_by_name["GetServerInfo"]
        request_type = symbol_database.Default().GetSymbol(rpc.input_type.full_name)
        message = _message({} if request is None else request, request_type, "GetServerInfo")
        return self._unary(self._info.GetServerInfo, "GetServerInfo", message, timeout)


def _responses(call: Any, stream: _Requests) -> Iterator[Any]:
    """The responses of a streaming call; a failure raises TactforceError
    (or the request stream's own exception); leaving early cancels the call."""
    try:
        yield from call
    except grpc.RpcError as error:
        raise stream.failure(error) from error
    finally:
        call.cancel()
