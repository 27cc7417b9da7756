// TLS and mutual TLS. Certificates are made at run time with the openssl
// CLI in a temporary directory (never committed): a CA, a server
// certificate for localhost / 127.0.0.1, a client certificate signed by the
// CA, and a client certificate signed by an unrelated CA.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/temp_dir.h"
#include "test_support.h"

namespace tactforce::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class Certificates {
 public:
  // Returns an empty string on success, else what failed.
  std::string Make() {
    if (temp_.path().empty()) return "mkdtemp failed";
    dir_ = temp_.path();
    std::ofstream(dir_ / "server.ext")
        << "subjectAltName=DNS:localhost,IP:127.0.0.1\nextendedKeyUsage=serverAuth\n";
    std::ofstream(dir_ / "client.ext") << "extendedKeyUsage=clientAuth\n";
    for (const char* ca : {"ca", "rogue-ca"}) {
      if (std::string e = Openssl(
              {"req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
               "-nodes", "-days", "2", "-keyout", Path(std::string(ca) + ".key"), "-out",
               Path(std::string(ca) + ".crt"), "-subj", std::string("/CN=tactforce-test-") + ca,
               "-addext", "basicConstraints=critical,CA:TRUE", "-addext",
               "keyUsage=critical,keyCertSign,cRLSign"});
          !e.empty())
        return e;
    }
    if (std::string e = Leaf("server", "localhost", "ca", "server.ext"); !e.empty()) return e;
    if (std::string e = Leaf("client", "tactforce-test-client", "ca", "client.ext"); !e.empty())
      return e;
    return Leaf("rogue-client", "tactforce-rogue-client", "rogue-ca", "client.ext");
  }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string Pem(const std::string& name) const { return ReadFile(dir_ / name); }

  std::shared_ptr<grpc::Channel> Channel(const std::string& address, const std::string& client) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = Pem("ca.crt");
    if (!client.empty()) {
      ssl.pem_private_key = Pem(client + ".key");
      ssl.pem_cert_chain = Pem(client + ".crt");
    }
    grpc::ChannelArguments args;
    args.SetSslTargetNameOverride("localhost");
    args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
    return Connect(address, grpc::SslCredentials(ssl), args);
  }

 private:
  std::string Openssl(std::vector<std::string> args) {
    args.insert(args.begin(), "/usr/bin/openssl");
    ProcessResult run = RunProcess(args);
    if (run.exit_code != 0) return "openssl " + args[1] + " failed: " + run.err;
    return "";
  }

  std::string Leaf(const std::string& name, const std::string& cn, const std::string& ca,
                   const std::string& ext) {
    if (std::string e = Openssl({"req", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
                                 "-nodes", "-keyout", Path(name + ".key"), "-out",
                                 Path(name + ".csr"), "-subj", "/CN=" + cn});
        !e.empty())
      return e;
    return Openssl({"x509", "-req", "-in", Path(name + ".csr"), "-CA", Path(ca + ".crt"), "-CAkey",
                    Path(ca + ".key"), "-CAcreateserial", "-days", "2", "-out", Path(name + ".crt"),
                    "-extfile", Path(ext)});
  }

  TempDir temp_{"tactforce_tls"};
  fs::path dir_;
};

grpc::Status PlanOnce(const std::shared_ptr<grpc::Channel>& channel) {
  auto stub = v1::Planner::NewStub(channel);
  v1::PlanResponse response;
  grpc::Status status = CallPlan(*stub, WrenchRequest(), &response, std::chrono::seconds(5));
  if (status.ok() && response.status() != v1::PLAN_STATUS_OPTIMAL)
    return grpc::Status(grpc::StatusCode::INTERNAL, "not optimal: " + response.message());
  return status;
}

TEST(TlsTest, MutualTlsAcceptsOnlyClientsSignedByTheCa) {
  Certificates certs;
  ASSERT_EQ(certs.Make(), "");
  std::string error;
  auto server =
      ServerProcess::Start({"--tls-cert", certs.Path("server.crt"), "--tls-key",
                            certs.Path("server.key"), "--tls-client-ca", certs.Path("ca.crt")},
                           &error);
  ASSERT_NE(server, nullptr) << error;

  grpc::Status status = PlanOnce(certs.Channel(server->address(), "client"));
  EXPECT_TRUE(status.ok()) << Describe(status);

  status = PlanOnce(certs.Channel(server->address(), ""));  // no client certificate
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << Describe(status);

  status = PlanOnce(certs.Channel(server->address(), "rogue-client"));  // other CA
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << Describe(status);

  status = PlanOnce(Connect(server->address()));  // plaintext
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << Describe(status);
  // gRPC's own lines about the failed handshakes go through the server's
  // logger (the counterpart of GrpcLinesFollowLogLevelOff below).
  EXPECT_TRUE(server->WaitForStderr("source=grpc", std::chrono::seconds(5)))
      << server->StderrText();

  // The Python client speaks mutual TLS too.
  ProcessResult python = RunProcess(
      {TACTFORCE_PYTHON3, (SourceDir() / "client/python/plan_client.py").string(), "--server",
       server->address(), "--tls-ca", certs.Path("ca.crt"), "--tls-cert", certs.Path("client.crt"),
       "--tls-key", certs.Path("client.key"), "--tls-server-name", "localhost", "--timeout", "10"},
      {std::string("PYTHONPATH=") + TACTFORCE_PYTHON_STUB_DIR});
  EXPECT_EQ(python.exit_code, 0) << python.err;
  EXPECT_THAT(python.out, HasSubstr("status: OPTIMAL"));

  EXPECT_EQ(server->Stop(), 0) << server->StderrText();
}

TEST(TlsTest, ServerOnlyTlsNeedsNoClientCertificate) {
  Certificates certs;
  ASSERT_EQ(certs.Make(), "");
  std::string error;
  auto server = ServerProcess::Start(
      {"--tls-cert", certs.Path("server.crt"), "--tls-key", certs.Path("server.key")}, &error);
  ASSERT_NE(server, nullptr) << error;
  grpc::Status status = PlanOnce(certs.Channel(server->address(), ""));
  EXPECT_TRUE(status.ok()) << Describe(status);
  status = PlanOnce(Connect(server->address()));  // plaintext
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << Describe(status);
  EXPECT_EQ(server->Stop(), 0) << server->StderrText();
}

// --log-level off: failed handshakes print nothing (gRPC's log lines
// follow the server's level).
TEST(TlsTest, GrpcLinesFollowLogLevelOff) {
  Certificates certs;
  ASSERT_EQ(certs.Make(), "");
  std::string error;
  auto server = ServerProcess::Start(
      {"--tls-cert", certs.Path("server.crt"), "--tls-key", certs.Path("server.key"),
       "--tls-client-ca", certs.Path("ca.crt"), "--log-level", "off"},
      &error);
  ASSERT_NE(server, nullptr) << error;
  EXPECT_EQ(PlanOnce(certs.Channel(server->address(), "")).error_code(),
            grpc::StatusCode::UNAVAILABLE);
  EXPECT_EQ(PlanOnce(Connect(server->address())).error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_TRUE(PlanOnce(certs.Channel(server->address(), "client")).ok());
  EXPECT_EQ(server->Stop(), 0);
  EXPECT_EQ(server->StderrText(), "");
}

}  // namespace
}  // namespace tactforce::testing
