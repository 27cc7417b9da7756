// Whole files: read with C stdio in binary mode (errno's text in the
// message), written to a temporary name beside the target and renamed over
// it when complete; byte offsets to line and column.
#include "tactforce/io/text_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "absl/strings/str_cat.h"

namespace tactforce::io {

std::string SourceName(const std::string& path) { return path == "-" ? "<stdin>" : path; }

absl::StatusOr<std::string> ReadTextFile(const std::string& path) {
  const bool standard_input = path == "-";
  std::FILE* file = standard_input ? stdin : std::fopen(path.c_str(), "rb");
  if (file == nullptr)
    return absl::InvalidArgumentError(absl::StrCat(path, ": cannot open: ", std::strerror(errno)));
  std::string bytes;
  char buffer[1 << 16];
  size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), file)) > 0) bytes.append(buffer, n);
  const int error = std::ferror(file) ? errno : 0;
  if (!standard_input) std::fclose(file);
  if (error != 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(SourceName(path), ": cannot read: ", std::strerror(error)));
  }
  return bytes;
}

namespace {

absl::Status WriteDirectly(const std::string& target, const std::string& named,
                           std::string_view text) {
  std::ofstream out(target, std::ios::binary);
  if (!out) return absl::InvalidArgumentError(absl::StrCat(named, ": cannot open for writing"));
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) return absl::InvalidArgumentError(absl::StrCat(named, ": write failed"));
  return absl::OkStatus();
}

}  // namespace

absl::Status WriteTextFile(const std::string& path, std::string_view text) {
  // Devices and pipes (/dev/stdout, a FIFO) cannot be replaced by a rename.
  struct stat info {};
  if (::stat(path.c_str(), &info) == 0 && !S_ISREG(info.st_mode))
    return WriteDirectly(path, path, text);
  static std::atomic<unsigned> counter{0};
  const std::string temporary =
      absl::StrCat(path, ".tmp-", ::getpid(), "-", counter.fetch_add(1, std::memory_order_relaxed));
  if (absl::Status written = WriteDirectly(temporary, path, text); !written.ok()) {
    std::remove(temporary.c_str());
    return written;
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    const int error = errno;
    std::remove(temporary.c_str());
    return absl::InvalidArgumentError(absl::StrCat(path, ": cannot write: ", std::strerror(error)));
  }
  return absl::OkStatus();
}

TextPosition PositionInText(std::string_view text, size_t offset) {
  const std::string_view before = text.substr(0, std::min(offset, text.size()));
  TextPosition p;
  p.line = 1 + static_cast<int>(std::count(before.begin(), before.end(), '\n'));
  const size_t line_start = before.rfind('\n');
  p.column = static_cast<int>(line_start == std::string_view::npos ? before.size() + 1
                                                                   : before.size() - line_start);
  return p;
}

}  // namespace tactforce::io
