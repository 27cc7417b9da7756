// What every subcommand shares: reading an input file or stdin, "x,y,z"
// vectors, and reporting an error as one line with its exit code.
#include "cli_common.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>
#include <vector>

#include "absl/strings/str_cat.h"

namespace tactforce::cli {

absl::StatusOr<std::string> ReadInput(const std::string& path, const std::string& flag) {
  if (path == "-") {
    std::ostringstream text;
    text << std::cin.rdbuf();
    if (std::cin.bad()) {
      return absl::InvalidArgumentError(absl::StrCat(flag, " -: cannot read standard input"));
    }
    return text.str();
  }
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return absl::InvalidArgumentError(
        absl::StrCat(flag, ": cannot read '", path, "': is a directory"));
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    return absl::InvalidArgumentError(
        absl::StrCat(flag, ": cannot read '", path, "': ", std::strerror(errno)));
  }
  std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (file.bad()) {
    return absl::InvalidArgumentError(
        absl::StrCat("--request: error while reading '", path, "'"));
  }
  return text;
}

int ExitCodeFor(absl::StatusCode code) {
  switch (code) {
    case absl::StatusCode::kOk:
      return kExitOk;
    case absl::StatusCode::kInvalidArgument:
      return kExitBadInput;
    case absl::StatusCode::kUnavailable:
      return kExitUnavailable;
    case absl::StatusCode::kDeadlineExceeded:
      return kExitDeadline;
    default:
      return kExitFailure;
  }
}

int ReportError(const absl::Status& status) {
  std::string message(status.message());
  for (char& c : message) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  switch (status.code()) {
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kUnavailable:
    case absl::StatusCode::kDeadlineExceeded:
      break;
    default:
      message = absl::StrCat(absl::StatusCodeToString(status.code()), ": ", message);
  }
  std::cerr << "error: " << message << std::endl;
  return ExitCodeFor(status.code());
}

absl::StatusOr<Eigen::Vector3d> ParseVec3(const std::string& text, const std::string& flag) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(x))
      return absl::InvalidArgumentError(absl::StrCat(flag, ": '", text, "' is not x,y,z"));
    v.push_back(x);
  }
  if (v.size() != 3) return absl::InvalidArgumentError(absl::StrCat(flag, ": '", text, "' is not x,y,z"));
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

}  // namespace tactforce::cli
