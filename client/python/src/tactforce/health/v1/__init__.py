"""health_pb2 and health_pb2_grpc: generated at build time from grpc-proto's
grpc/health/v1/health.proto (see tactforce.health)."""
