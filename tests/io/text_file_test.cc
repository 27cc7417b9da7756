// io/text_file.h (whole files, byte offsets to line and column) and the
// readers built on it: CSV and meshes report a missing file the same way.
#include "tactforce/io/text_file.h"

#include <unistd.h>

#include <filesystem>
#include <string>

#include "gtest/gtest.h"
#include "tactforce/io/csv.h"
#include "tactforce/io/mesh.h"
#include "support/temp_dir.h"

namespace tactforce::io {
namespace {

namespace fs = std::filesystem;

class IoTextFile : public ::testing::Test {
 protected:
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  tactforce::testing::TempDir temp_{"tactforce_io_text_file"};
  fs::path dir_ = temp_.path();
};

TEST_F(IoTextFile, ReadsBackExactlyTheBytesWritten) {
  const std::string bytes("line\r\n\0nul\xff\xfe\n", 13);
  ASSERT_TRUE(WriteTextFile(Path("bytes.bin"), bytes).ok());
  absl::StatusOr<std::string> back = ReadTextFile(Path("bytes.bin"));
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(*back, bytes);  // no newline translation, NUL kept
  ASSERT_TRUE(WriteTextFile(Path("empty.txt"), "").ok());
  EXPECT_EQ(*ReadTextFile(Path("empty.txt")), "");
}

TEST_F(IoTextFile, ErrorsNameThePathAndTheReason) {
  const std::string missing = Path("missing.json");
  absl::StatusOr<std::string> r = ReadTextFile(missing);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(r.status().message(), missing + ": cannot open: No such file or directory");
  r = ReadTextFile(dir_.string());  // a folder opens but cannot be read
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(), dir_.string() + ": cannot read: Is a directory");
  const std::string nowhere = Path("no_such_dir/out.txt");
  absl::Status w = WriteTextFile(nowhere, "x");
  EXPECT_EQ(w.message(), nowhere + ": cannot open for writing");
}

// Written to a temporary name and renamed: a replaced file is whole, no
// temporary is left behind, a failed write keeps the old contents, and a
// device is written in place.
TEST_F(IoTextFile, WritesAtomicallyAndLeavesNoTemporaries) {
  const std::string path = Path("out.csv");
  ASSERT_TRUE(WriteTextFile(path, "old\n").ok());
  ASSERT_TRUE(WriteTextFile(path, "new\n").ok());
  EXPECT_EQ(*ReadTextFile(path), "new\n");
  int entries = 0;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    ++entries;
    EXPECT_EQ(entry.path().filename(), "out.csv");
  }
  EXPECT_EQ(entries, 1);
  fs::create_directories(Path("folder"));
  EXPECT_FALSE(WriteTextFile(Path("folder"), "x").ok());  // cannot replace a folder by a file
  EXPECT_TRUE(fs::is_directory(Path("folder")));
  EXPECT_TRUE(WriteTextFile("/dev/null", "discarded").ok());
}

// The CSV and mesh readers read through ReadTextFile: one wording.
TEST_F(IoTextFile, CsvAndMeshReadersShareTheWording) {
  const std::string csv = Path("run.csv");
  EXPECT_EQ(ReadCsvFile(csv).status().message(), csv + ": cannot open: No such file or directory");
  const std::string mesh = Path("part.stl");
  EXPECT_EQ(ReadMeshFile(mesh).status().message(),
            mesh + ": cannot open: No such file or directory");
  const std::string descriptor = Path("part.mesh.json");
  EXPECT_EQ(ReadMeshDescriptor(descriptor).status().message(),
            descriptor + ": cannot open: No such file or directory");
}

TEST(IoTextPosition, LineAndColumnOfAByteOffset) {
  const std::string text = "ab\ncd\n\nx";
  auto at = [&](size_t offset) {
    const TextPosition p = PositionInText(text, offset);
    return std::make_pair(p.line, p.column);
  };
  EXPECT_EQ(at(0), std::make_pair(1, 1));
  EXPECT_EQ(at(1), std::make_pair(1, 2));
  EXPECT_EQ(at(2), std::make_pair(1, 3));  // the line break ends line 1
  EXPECT_EQ(at(3), std::make_pair(2, 1));
  EXPECT_EQ(at(6), std::make_pair(3, 1));  // an empty line
  EXPECT_EQ(at(7), std::make_pair(4, 1));
  EXPECT_EQ(at(8), std::make_pair(4, 2));    // the end: after the last byte
  EXPECT_EQ(at(100), std::make_pair(4, 2));  // past the end: the same
  EXPECT_EQ(PositionInText("", 0).line, 1);
  EXPECT_EQ(PositionInText("", 0).column, 1);
}

}  // namespace
}  // namespace tactforce::io
