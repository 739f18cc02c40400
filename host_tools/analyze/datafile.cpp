#include "datafile.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>

namespace gyrochar {

bool is_regular_file(const std::string& path) {
  struct stat st {};
  return path != "-" && stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

DataFile::DataFile(const std::string& path, unsigned column) : column_(column) {
  if (column == 0) throw DataFileError("column numbers start at 1", 0);
  if (path == "-") {
    file_ = gzdopen(dup(STDIN_FILENO), "rb");
  } else {
    struct stat st {};
    if (stat(path.c_str(), &st) != 0) throw DataFileError(std::strerror(errno), 0);
    if (S_ISDIR(st.st_mode)) throw DataFileError("is a directory", 0);
    size_ = static_cast<std::uint64_t>(st.st_size);
    errno = 0;
    file_ = gzopen(path.c_str(), "rb");
    if (file_ == nullptr) throw DataFileError(std::strerror(errno ? errno : EIO), 0);
  }
  if (file_ == nullptr) throw DataFileError("cannot read standard input", 0);
  gzbuffer(file_, 1 << 17);
}

DataFile::~DataFile() {
  if (file_ != nullptr) gzclose(file_);
}

std::uint64_t DataFile::bytes_read() const {
  const auto offset = gzoffset(file_);
  return offset < 0 ? 0 : static_cast<std::uint64_t>(offset);
}

bool DataFile::read_line() {
  buffer_.clear();
  char chunk[4096];
  while (gzgets(file_, chunk, sizeof chunk) != nullptr) {
    buffer_ += chunk;
    if (!buffer_.empty() && buffer_.back() == '\n') break;
  }
  if (buffer_.empty() || buffer_.back() != '\n') {
    // End of input or a failure. Z_BUF_ERROR is a gzip stream cut short: its last line may be cut
    // too, so it is an error, not the end of the data.
    int err = Z_OK;
    const char* message = gzerror(file_, &err);
    if (err != Z_OK) throw DataFileError(std::string("read error: ") + message, line_ + 1);
  }
  if (buffer_.empty()) return false;
  ++line_;
  return true;
}

LineKind parse_data_line(std::string_view line, unsigned column, double& value, unsigned& fields) {
  if (const auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
  auto is_sep = [](char c) { return c == ' ' || c == '\t' || c == ',' || c == ';' || c == '\r' || c == '\n'; };
  const char* p = line.data();
  const char* const end = p + line.size();
  fields = 0;
  const char* token = nullptr;
  const char* token_end = nullptr;
  while (p < end) {
    while (p < end && is_sep(*p)) ++p;
    if (p == end) break;
    const char* start = p;
    while (p < end && !is_sep(*p)) ++p;
    if (++fields == column) {
      token = start;
      token_end = p;
      break;
    }
  }
  if (fields == 0) return LineKind::blank;
  if (token == nullptr) return LineKind::missing_column;
  if (*token == '+') ++token;
  const auto [ptr, ec] = std::from_chars(token, token_end, value);
  if (ec != std::errc() || ptr != token_end || !std::isfinite(value)) return LineKind::not_a_number;
  return LineKind::value;
}

bool DataFile::next(double& value) {
  while (read_line()) {
    unsigned fields = 0;
    switch (parse_data_line(buffer_, column_, value, fields)) {
      case LineKind::value:
        seen_value_ = true;
        return true;
      case LineKind::blank:
        if (!seen_value_ && !buffer_.empty() && buffer_[0] == '#' && header_.size() < max_header_lines) {
          std::string text = buffer_;
          while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
          header_.push_back(std::move(text));
        }
        continue;
      case LineKind::missing_column:
        throw DataFileError("line has " + std::to_string(fields) + " column(s), column " +
                                std::to_string(column_) + " was asked for", line_);
      case LineKind::not_a_number: {
        std::string text = buffer_;
        while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
        throw DataFileError("not a finite number in column " + std::to_string(column_) + ": '" + text + "'", line_);
      }
    }
  }
  return false;
}

}  // namespace gyrochar
