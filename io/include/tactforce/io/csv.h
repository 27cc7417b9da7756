// Numeric CSV tables with a header row, columns addressed by name. Errors
// name the file, line and column ("run.csv:12: column 'fx': not a number").
#pragma once

#include <map>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace tactforce::io {

struct CsvTable {
  std::string source;                // file name (for messages)
  std::vector<std::string> columns;  // header, in file order
  std::vector<std::vector<double>> rows;
  std::vector<int> line_numbers;  // 1-based file line of each row
  int skipped_rows = 0;           // rows dropped by skip_nan_rows

  int ColumnIndex(const std::string& name) const;  // -1 when absent
  bool Has(const std::string& name) const { return ColumnIndex(name) >= 0; }
  std::vector<double> Column(const std::string& name) const;
  // InvalidArgument "<source>: missing column(s) a, b" when any is absent.
  absl::Status Require(const std::vector<std::string>& names) const;
};

struct CsvOptions {
  // Rows with an empty/NaN field: error (false) or skipped and counted (true).
  bool skip_nan_rows = false;
};

absl::StatusOr<CsvTable> ParseCsv(const std::string& text, const std::string& source,
                                  const CsvOptions& options = {});
absl::StatusOr<CsvTable> ReadCsvFile(const std::string& path, const CsvOptions& options = {});

}  // namespace tactforce::io
