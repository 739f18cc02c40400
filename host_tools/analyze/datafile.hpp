#pragma once
// Streaming reader for recorded data files: one value per line or a chosen whitespace/comma
// separated column, '#' comments and blank lines skipped, plain or gzip-compressed (detected from
// the content), or standard input. Memory is one line; files of any length stream through.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <zlib.h>

namespace gyrochar {

/// A data file problem, with the line where it happened (0 when not tied to a line).
class DataFileError : public std::runtime_error {
 public:
  DataFileError(const std::string& what, std::uint64_t line) : std::runtime_error(what), line_(line) {}
  std::uint64_t line() const { return line_; }

 private:
  std::uint64_t line_;
};

/// True when `path` names a regular file (which can be read twice: once to count the values);
/// false for "-" (standard input), pipes, devices and paths that do not exist. O(1).
bool is_regular_file(const std::string& path);

/// Result of parsing one line of a data file.
enum class LineKind { value, blank, missing_column, not_a_number };

/// Parses one line: fields separated by blanks, commas or semicolons, '#' starts a comment.
/// Sets `value` from field `column` (1-based) when it returns LineKind::value; `fields` receives
/// the number of fields seen. O(line length), no allocation.
LineKind parse_data_line(std::string_view line, unsigned column, double& value, unsigned& fields);

class DataFile {
 public:
  /// Opens `path` ("-" for standard input). column is 1-based. Throws DataFileError when the file
  /// cannot be opened (the message carries the system's reason).
  DataFile(const std::string& path, unsigned column = 1);
  ~DataFile();
  DataFile(const DataFile&) = delete;
  DataFile& operator=(const DataFile&) = delete;

  /// Reads the next value into `value`; false at the end of the data. Throws DataFileError on a
  /// line whose column is missing or is not a finite number, and on a read error (a gzip stream
  /// cut short or corrupted included: its last line cannot be trusted). O(line length), no
  /// allocation after the first lines (the line buffer is reused).
  bool next(double& value);

  /// Line number of the last value read (1-based, counting comments and blank lines).
  std::uint64_t line() const { return line_; }
  /// Bytes of the underlying file consumed so far (compressed bytes for gzip), for progress.
  std::uint64_t bytes_read() const;
  /// Size of the file in bytes, 0 when unknown (standard input, pipes).
  std::uint64_t size_bytes() const { return size_; }
  /// The '#' lines before the first value (at most 64, without their line ends): where a
  /// producer such as gyrochar-sim describes the data.
  const std::vector<std::string>& header() const { return header_; }

 private:
  bool read_line();

  gzFile file_ = nullptr;
  unsigned column_;
  std::uint64_t line_ = 0;
  std::uint64_t size_ = 0;
  std::string buffer_;
  bool seen_value_ = false;
  static constexpr std::size_t max_header_lines = 64;
  std::vector<std::string> header_;
};

}  // namespace gyrochar
