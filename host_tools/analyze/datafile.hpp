#pragma once
// The data file reader of gyrochar-analyze: numbers, one per line or one column of a table, from a
// file (plain or gzip, told by its content) or from standard input, read once, in blocks.
//
// Text is read 1 MiB at a time (gzip through zlib's inflate into the same buffer) and parsed in
// place: an integer is read digit by digit, anything else by std::from_chars. Memory is the
// buffer and one block of values, whatever the length of the file.
//
// The reader never guesses silently. The first data line fixes the layout (how many fields, and
// which column holds the values) and every later data line must have the same number of fields:
//   - fields are separated by blanks, or by ',' or ';' (blanks around them allowed); '#' or '%'
//     (SigmaTheta's .ykt files) starts a comment; blank and comment lines are skipped (the '#'
//     lines before the first value are kept: header());
//   - a comma between two digits on a line that also has another separator is a decimal comma:
//     refused, never read as two numbers ("0,5;1,5"); on a line of bare commas ("1,288185") it
//     could be either, so a table like that needs --column (column > 0);
//   - without a column (column 0) a one-field file is read as is; a two-field table whose first
//     column increases over the first lines of the file (time stamps) is read from column 2, and
//     layout_note() says so; any other table is refused with a hint to --column;
//   - a value must be a finite number; bytes that are not text (NUL, other control characters)
//     are refused; quoted input in an error shows such bytes as \xNN and at most 40 characters.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace gyrochar {

/// A data file problem, with the line where it happened (0 when not tied to a line). what() is a
/// sentence without the file name (the caller names the file).
class DataFileError : public std::runtime_error {
 public:
  DataFileError(const std::string& what, std::uint64_t line) : std::runtime_error(what), line_(line) {}
  std::uint64_t line() const { return line_; }

 private:
  std::uint64_t line_;
};

class DataFile {
 public:
  /// Opens `path` ("-": standard input). `column` is 1-based; 0 lets the reader choose (see
  /// above). Throws DataFileError when the file cannot be opened (the system's reason) or is a
  /// directory. Allocates the 1 MiB buffer.
  explicit DataFile(const std::string& path, unsigned column = 0);
  ~DataFile();
  DataFile(const DataFile&) = delete;
  DataFile& operator=(const DataFile&) = delete;

  /// Reads the next values, in order, into `out`; returns how many (0: the end of the data).
  /// O(bytes read), no allocation. Throws DataFileError on a line that breaks the rules above, on
  /// a read error, and on a gzip stream that is corrupt or cut short (its last line cannot be
  /// trusted); the values the failed call had read are not returned.
  std::size_t read(std::span<double> out);
  /// One value: read() of one. false at the end of the data.
  bool next(double& value) { return read({&value, 1}) == 1; }

  /// Line (1-based, comments and blank lines counted) of out[i] of the last read().
  std::uint64_t line_of(std::size_t i) const;
  /// The column the values come from (1-based); 0 until the first value is read.
  unsigned column() const;
  /// When the reader chose the column of a table: a sentence saying which and why; else empty.
  const std::string& layout_note() const;
  /// The '#' lines before the first value (at most 64, without their line ends): where a
  /// producer such as gyrochar-sim describes the data.
  const std::vector<std::string>& header() const;

  /// An upper bound on the number of values, from the file's size (a value takes at least 2
  /// bytes; gzip: the size recorded in its trailer, which is modulo 2^32 and that of the last
  /// member only: a hint); 0 when unknown (standard input, pipes). O(1).
  std::uint64_t values_bound() const;
  /// Bytes of the file consumed so far (compressed bytes for gzip), and its size (0: unknown).
  std::uint64_t bytes_read() const;
  std::uint64_t size_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gyrochar
