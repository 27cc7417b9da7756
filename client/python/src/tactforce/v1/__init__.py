"""Generated protobuf and gRPC modules of the tactforce.v1 protos.

One ``<name>_pb2`` (messages) and ``<name>_pb2_grpc`` (stubs) per
``proto/tactforce/v1/<name>.proto``, written here at build time by protoc
and grpc_python_plugin (client/python/setup.py, or the CMake target
tactforce_python_stubs); the source tree holds none of them.
"""
