// What every subcommand shares: reading an input file or stdin, "x,y,z"
// vectors, and reporting an error as one line with its exit code.
#include "cli_common.h"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

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
    return absl::InvalidArgumentError(absl::StrCat(flag, ": error while reading '", path, "'"));
  }
  return text;
}

void AddOutputFlags(CLI::App* cmd, OutputFormat* out, const std::string& json_what) {
  CLI::Option* json =
      cmd->add_flag("--json", out->json_flag, "Print " + json_what + " as JSON instead of a table");
  cmd->add_option("--format", out->format, "Output: table or json (--json)")
      ->check(CLI::IsMember({"table", "json"}))
      ->capture_default_str()
      ->excludes(json);
}

void AddRecordingClockFlags(CLI::App* cmd, double* seconds, double* rate) {
  cmd->add_option("--seconds", *seconds, "Duration (s)")
      ->check(Between(0.1, 86400))
      ->capture_default_str();
  cmd->add_option("--rate", *rate, "Sample rate (Hz)")
      ->check(Between(1, 1e5))
      ->capture_default_str();
}

namespace {

// A validator of finite numbers for which `ok` holds; `rule` is "must be >= 1".
CLI::Validator NumberCheck(std::function<bool(double)> ok, const std::string& rule,
                           const std::string& name) {
  return CLI::Validator(
      [ok, rule](std::string& text) -> std::string {
        char* end = nullptr;
        const double x = std::strtod(text.c_str(), &end);
        if (text.empty() || end != text.c_str() + text.size())
          return absl::StrCat("'", text, "' is not a number");
        if (!std::isfinite(x) || !ok(x)) return absl::StrCat(rule, ", got ", text);
        return std::string();
      },
      rule, name);
}

std::string Number(double x) { return absl::StrFormat("%g", x); }

bool Matches(const std::string& name, const std::string& pattern) {
  const size_t star = pattern.find('*');
  if (star == std::string::npos) return name == pattern;
  const std::string prefix = pattern.substr(0, star), suffix = pattern.substr(star + 1);
  return name.size() >= prefix.size() + suffix.size() &&
         name.compare(0, prefix.size(), prefix) == 0 &&
         name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

CLI::Validator AtLeast(double min) {
  return NumberCheck([min](double x) { return x >= min; }, "must be >= " + Number(min), "AT_LEAST");
}
CLI::Validator GreaterThan(double min) {
  return NumberCheck([min](double x) { return x > min; }, "must be > " + Number(min),
                     "GREATER_THAN");
}
CLI::Validator Between(double min, double max) {
  return NumberCheck([min, max](double x) { return x >= min && x <= max; },
                     absl::StrCat("must be in [", Number(min), ", ", Number(max), "]"), "BETWEEN");
}

absl::Status PrepareOutputDir(const std::string& dir, bool force,
                              const std::vector<std::string>& patterns, const std::string& flag,
                              const std::string& whose) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) {
    return absl::InvalidArgumentError(
        absl::StrCat(flag, ": '", dir, "' exists and is not a folder"));
  }
  fs::create_directories(dir, ec);
  if (ec)
    return absl::InvalidArgumentError(
        absl::StrCat(flag, ": cannot create '", dir, "': ", ec.message()));
  std::vector<fs::path> ours;
  int others = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    bool match = false;
    for (const std::string& p : patterns) match = match || Matches(name, p);
    if (match && entry.is_regular_file()) {
      ours.push_back(entry.path());
    } else {
      ++others;
    }
  }
  if (ec)
    return absl::InvalidArgumentError(
        absl::StrCat(flag, ": cannot list '", dir, "': ", ec.message()));
  if (ours.empty() && others == 0) return absl::OkStatus();
  if (!force) {
    return absl::InvalidArgumentError(
        absl::StrCat(flag, ": '", dir, "' is not empty (", ours.size() + others, " entries",
                     ours.empty() ? "" : absl::StrCat(", e.g. ", ours.front().filename().string()),
                     "); choose an empty folder, or --force to replace ", whose, " files"));
  }
  for (const fs::path& p : ours) {
    if (!fs::remove(p, ec) || ec) {
      return absl::InvalidArgumentError(
          absl::StrCat(flag, ": cannot remove '", p.string(), "': ", ec.message()));
    }
  }
  return absl::OkStatus();
}

std::string InputName(const std::string& path) { return path == "-" ? "<stdin>" : path; }

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
  if (v.size() != 3)
    return absl::InvalidArgumentError(absl::StrCat(flag, ": '", text, "' is not x,y,z"));
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

absl::Status CheckPlotPath(const std::string& path, const std::string& flag) {
  if (path.empty()) return absl::OkStatus();
  const std::filesystem::path file(path);
  if (absl::AsciiStrToLower(file.extension().string()) != ".svg") {
    return absl::InvalidArgumentError(absl::StrCat(
        flag, ": '", path, "': pictures are SVG; give a .svg name (rsvg-convert makes a PNG)"));
  }
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec))
    return absl::InvalidArgumentError(
        absl::StrCat(flag, ": cannot write '", path, "': it is a directory"));
  const std::string folder = file.parent_path().empty() ? "." : file.parent_path().string();
  if (!std::filesystem::is_directory(folder, ec))
    return absl::InvalidArgumentError(
        absl::StrCat(flag, ": directory '", folder, "' of '", path, "' does not exist"));
  if (::access(folder.c_str(), W_OK) != 0)
    return absl::InvalidArgumentError(
        absl::StrCat(flag, ": cannot write '", path, "': ", std::strerror(errno)));
  return absl::OkStatus();
}

}  // namespace tactforce::cli
