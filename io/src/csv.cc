// Numeric CSV (csv.h): a header row, comma-separated cells trimmed of blanks,
// '#' comment lines and blank lines skipped; every error names file:line.
#include "tactforce/io/csv.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "tactforce/io/text_file.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::io {
namespace {

std::vector<std::string> SplitLine(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) {
    const size_t b = cell.find_first_not_of(" \t\r");
    const size_t e = cell.find_last_not_of(" \t\r");
    out.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
  }
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

}  // namespace

int CsvTable::ColumnIndex(const std::string& name) const {
  for (size_t i = 0; i < columns.size(); ++i) {
    if (columns[i] == name) return static_cast<int>(i);
  }
  return -1;
}

std::vector<double> CsvTable::Column(const std::string& name) const {
  const int c = ColumnIndex(name);
  std::vector<double> out;
  if (c < 0) return out;
  out.reserve(rows.size());
  for (const auto& r : rows) out.push_back(r[c]);
  return out;
}

absl::Status CsvTable::Require(const std::vector<std::string>& names) const {
  std::vector<std::string> missing;
  for (const auto& n : names) {
    if (!Has(n)) missing.push_back(n);
  }
  if (missing.empty()) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrCat(source, ": missing column(s) ", absl::StrJoin(missing, ", ")));
}

absl::StatusOr<CsvTable> ParseCsv(const std::string& text, const std::string& source,
                                  const CsvOptions& options) {
  CsvTable table;
  table.source = source;
  std::istringstream in(text);
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    std::vector<std::string> cells = SplitLine(line);
    if (table.columns.empty()) {
      for (const auto& c : cells) {
        if (c.empty())
          return absl::InvalidArgumentError(
              absl::StrCat(source, ":", line_number, ": empty column name"));
      }
      table.columns = cells;
      continue;
    }
    if (cells.size() != table.columns.size()) {
      return absl::InvalidArgumentError(absl::StrCat(source, ":", line_number, ": ", cells.size(),
                                                     " fields, header has ", table.columns.size()));
    }
    std::vector<double> row(cells.size());
    bool has_nan = false;
    for (size_t c = 0; c < cells.size(); ++c) {
      const std::string& s = cells[c];
      if (s.empty() || s == "nan" || s == "NaN" || s == "NAN") {
        has_nan = true;
        row[c] = std::nan("");
        continue;
      }
      char* end = nullptr;
      errno = 0;
      row[c] = std::strtod(s.c_str(), &end);
      if (end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(row[c])) {
        return absl::InvalidArgumentError(absl::StrCat(source, ":", line_number, ": column '",
                                                       table.columns[c], "': not a number ('", s,
                                                       "')"));
      }
    }
    if (has_nan) {
      if (options.skip_nan_rows) {
        ++table.skipped_rows;
        continue;
      }
      for (size_t c = 0; c < row.size(); ++c) {
        if (std::isnan(row[c]))
          return absl::InvalidArgumentError(absl::StrCat(source, ":", line_number, ": column '",
                                                         table.columns[c], "': missing or NaN"));
      }
    }
    table.rows.push_back(std::move(row));
    table.line_numbers.push_back(line_number);
  }
  if (table.columns.empty())
    return absl::InvalidArgumentError(absl::StrCat(source, ": empty (no header)"));
  return table;
}

absl::StatusOr<CsvTable> ReadCsvFile(const std::string& path, const CsvOptions& options) {
  TF_ASSIGN_OR_RETURN(std::string text, ReadTextFile(path));
  return ParseCsv(text, SourceName(path), options);
}

}  // namespace tactforce::io
