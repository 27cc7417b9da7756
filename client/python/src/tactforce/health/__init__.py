"""The standard gRPC health-checking protocol (proto package grpc.health.v1),
generated into the tactforce package (tactforce.health.v1.health_pb2,
health_pb2_grpc) rather than a top-level `grpc` folder, which would shadow
the real grpc package. The wire names are the standard ones
(/grpc.health.v1.Health/Check)."""
