#include "datafile.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <new>
#include <string_view>

namespace gyrochar {

namespace {

constexpr std::size_t text_capacity = std::size_t{1} << 20;  // also the longest line
constexpr std::size_t gzip_input_capacity = std::size_t{1} << 18;
constexpr std::size_t max_header_lines = 64;
constexpr std::size_t layout_lookahead = 64;  // data lines that show a time stamp column

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r'; }
bool is_digit(char c) { return static_cast<unsigned char>(c - '0') < 10; }

// Up to 40 characters of `text` for an error message, bytes outside printable ASCII as \xNN.
std::string quoted(std::string_view text) {
  static constexpr char hex[] = "0123456789abcdef";
  std::string out = "'";
  for (std::size_t i = 0; i < text.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out + (text.size() > 40 ? "...'" : "'");
}

// A whole field as a finite number: [+-]digits (up to 18: exact) or what std::from_chars reads.
bool parse_number(const char* begin, const char* end, double& value) {
  const char* p = begin;
  const bool negative = p < end && *p == '-';
  if (p < end && (*p == '-' || *p == '+')) ++p;
  if (end - p >= 1 && end - p <= 18) {
    std::uint64_t v = 0;
    const char* q = p;
    while (q < end && is_digit(*q)) v = v * 10 + static_cast<unsigned>(*q++ - '0');
    if (q == end) {
      value = negative ? -static_cast<double>(v) : static_cast<double>(v);
      return true;
    }
  }
  if (begin < end && *begin == '+') ++begin;  // from_chars takes '-' only
  const auto [ptr, ec] = std::from_chars(begin, end, value);
  return ec == std::errc() && ptr == end && std::isfinite(value);
}

// A comment runs from '#' or '%' (SigmaTheta's .ykt files, MATLAB) to the end of the line.
bool is_comment(char c) { return c == '#' || c == '%'; }

// One line split into fields: blanks, or ',' or ';' with optional blanks around them, separate
// fields; a comment ends the line.
struct Fields {
  unsigned count = 0;
  std::string_view first, chosen;                  // field 1 and field `column`
  bool bare_comma = false;                         // a ',' between two digits
  bool other_separator = false;                    // any separator that is not such a comma
  bool point = false;                              // a '.' or an exponent in some field: ',' cannot be decimal
  std::size_t binary_at = std::string_view::npos;  // offset of a control byte
};

Fields split(std::string_view line, unsigned column) {
  Fields f;
  const char* const b = line.data();
  const char* const e = b + line.size();
  for (const char* q = b; q < e; ++q) {
    const auto c = static_cast<unsigned char>(*q);
    if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7f) {
      f.binary_at = static_cast<std::size_t>(q - b);
      return f;
    }
  }
  const char* p = b;
  while (p < e && is_blank(*p)) ++p;
  if (p < e && is_comment(*p)) return f;
  bool expect_field = false;  // a hard separator was seen: a field follows, even an empty one
  while (p < e && !is_comment(*p)) {
    const char* start = p;
    while (p < e && !is_blank(*p) && *p != ',' && *p != ';' && !is_comment(*p)) {
      if (*p == '.' || *p == 'e' || *p == 'E') f.point = true;
      ++p;
    }
    const std::string_view field(start, static_cast<std::size_t>(p - start));
    ++f.count;
    if (f.count == 1) f.first = field;
    if (f.count == column) f.chosen = field;
    expect_field = false;
    const char* blanks = p;
    while (p < e && is_blank(*p)) ++p;
    const bool had_blanks = p > blanks;
    if (p < e && (*p == ',' || *p == ';')) {
      if (*p == ',' && !had_blanks && p > b && is_digit(p[-1]) && p + 1 < e && is_digit(p[1])) f.bare_comma = true;
      else f.other_separator = true;
      ++p;
      while (p < e && is_blank(*p)) ++p;
      expect_field = true;
    } else if (had_blanks && p < e && !is_comment(*p)) {
      f.other_separator = true;
    }
  }
  if (expect_field) {  // "1,2," ends with an empty field
    ++f.count;
    if (f.count == column) f.chosen = {};
  }
  return f;
}

// The source of bytes: a file descriptor, through zlib's inflate when the data is gzip.
class Source {
 public:
  ~Source() {
    if (inflating_) inflateEnd(&z_);
    if (fd_ >= 0 && fd_ != STDIN_FILENO) close(fd_);
  }
  void open(const std::string& path) {
    if (path == "-") {
      fd_ = STDIN_FILENO;
    } else {
      fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
      if (fd_ < 0) throw DataFileError(std::strerror(errno), 0);
    }
    struct stat st {};
    if (fstat(fd_, &st) != 0) throw DataFileError(std::strerror(errno), 0);
    if (S_ISDIR(st.st_mode)) throw DataFileError("is a directory", 0);
    if (S_ISREG(st.st_mode)) {
      size_ = static_cast<std::uint64_t>(st.st_size);
      posix_fadvise(fd_, 0, 0, POSIX_FADV_SEQUENTIAL);
    }
  }

  // Reads the first bytes into `out` and decides: gzip (magic 1f 8b) or plain. Returns the
  // plain bytes placed in `out`.
  std::size_t start(char* out, std::size_t capacity) {
    input_ = std::make_unique<unsigned char[]>(gzip_input_capacity);
    std::size_t have = 0;
    while (have < 2) {
      const std::size_t n = read_fd(input_.get() + have, gzip_input_capacity - have);
      if (n == 0) break;
      have += n;
    }
    if (have >= 2 && input_[0] == 0x1f && input_[1] == 0x8b) {
      if (size_ >= 4) {
        unsigned char trailer[4];
        if (pread(fd_, trailer, 4, static_cast<off_t>(size_ - 4)) == 4)
          gzip_size_ = trailer[0] | trailer[1] << 8 | trailer[2] << 16 | std::uint64_t{trailer[3]} << 24;
      }
      z_.next_in = input_.get();
      z_.avail_in = static_cast<uInt>(have);
      if (inflateInit2(&z_, 15 + 16) != Z_OK) throw std::bad_alloc();
      inflating_ = true;
      return fill(out, capacity);
    }
    const std::size_t n = std::min(have, capacity);
    std::memcpy(out, input_.get(), n);
    input_.reset();
    return n;
  }

  // Up to `capacity` more bytes of text; 0 at the end. Throws DataFileError on read errors and
  // on gzip data that is corrupt, cut short, or followed by bytes that are not gzip.
  std::size_t fill(char* out, std::size_t capacity) {
    if (!inflating_) return read_fd(out, capacity);
    z_.next_out = reinterpret_cast<Bytef*>(out);
    z_.avail_out = static_cast<uInt>(capacity);
    while (z_.avail_out > 0) {
      if (z_.avail_in == 0 && !input_done_) {
        z_.next_in = input_.get();
        z_.avail_in = static_cast<uInt>(read_fd(input_.get(), gzip_input_capacity));
        input_done_ = z_.avail_in == 0;
      }
      if (member_done_) {  // another gzip member may follow (concatenated files), nothing else
        if (z_.avail_in == 0) break;
        if (z_.next_in[0] != 0x1f) throw DataFileError("bytes after the end of the gzip data", 0);
        inflateReset(&z_);
        member_done_ = false;
      }
      const int r = inflate(&z_, Z_NO_FLUSH);
      if (r == Z_STREAM_END) {
        member_done_ = true;
      } else if (r == Z_DATA_ERROR) {
        throw DataFileError(std::string("corrupt gzip data: ") + (z_.msg ? z_.msg : "invalid"), 0);
      } else if (r == Z_MEM_ERROR) {
        throw std::bad_alloc();
      } else if (r == Z_BUF_ERROR && input_done_) {
        throw DataFileError("unexpected end of file: the gzip data is cut short", 0);
      }
    }
    return capacity - z_.avail_out;
  }

  std::uint64_t consumed() const { return inflating_ ? consumed_ - z_.avail_in : consumed_; }
  std::uint64_t size() const { return size_; }
  std::uint64_t text_size_hint() const { return inflating_ ? std::max(gzip_size_, size_) : size_; }

 private:
  std::size_t read_fd(void* out, std::size_t capacity) {
    for (;;) {
      const ssize_t n = ::read(fd_, out, capacity);
      if (n >= 0) {
        consumed_ += static_cast<std::uint64_t>(n);
        return static_cast<std::size_t>(n);
      }
      if (errno != EINTR) throw DataFileError(std::string("read error: ") + std::strerror(errno), 0);
    }
  }

  int fd_ = -1;
  std::uint64_t size_ = 0, consumed_ = 0, gzip_size_ = 0;
  std::unique_ptr<unsigned char[]> input_;
  z_stream z_{};
  bool inflating_ = false, input_done_ = false, member_done_ = false;
};

}  // namespace

struct DataFile::Impl {
  Source source;
  std::unique_ptr<char[]> text{new char[text_capacity + 1]};  // + 1: a '\n' after the last byte
  std::size_t begin = 0, end = 0;                             // unparsed text
  bool at_end = false;                                        // the source has no more bytes
  std::uint64_t line = 0;                                     // lines consumed
  unsigned column_asked = 0, column = 0, fields = 0;          // fields: 0 until the first data line
  std::uint64_t first_data_line = 0;
  bool values_seen = false;
  std::vector<std::uint64_t> lines;  // line of each value of the last read()
  std::vector<std::string> header;
  std::string note;

  // Moves the unparsed text to the front and appends what the source has. false at the end.
  bool refill() {
    if (at_end) return false;
    if (begin > 0) {
      std::memmove(text.get(), text.get() + begin, end - begin);
      end -= begin;
      begin = 0;
    }
    if (end == text_capacity)
      throw DataFileError("longer than " + std::to_string(text_capacity >> 20) + " MiB: not a text data file?", line + 1);
    const std::size_t n = source.fill(text.get() + end, text_capacity - end);
    end += n;
    text[end] = '\n';
    at_end = n == 0;
    return n > 0;
  }

  // Whether column 1 of the data lines after the first (within the buffer) increases: the first
  // of a two-field table is then a time stamp. `from` is where the line after the first starts.
  bool first_column_increases(std::string_view first, std::size_t from) const {
    double previous = 0;
    if (!parse_number(first.data(), first.data() + first.size(), previous)) return false;
    std::size_t seen = 0;
    for (std::size_t p = from; p < end && seen < layout_lookahead;) {
      const char* nl = static_cast<const char*>(std::memchr(text.get() + p, '\n', end - p));
      if (nl == nullptr && !at_end) break;  // a line cut by the end of the buffer
      const std::size_t stop = nl ? static_cast<std::size_t>(nl - text.get()) : end;
      const Fields f = split({text.get() + p, stop - p}, 2);
      p = stop + 1;
      if (f.count == 0) continue;
      double v = 0;
      if (f.count != 2 || f.binary_at != std::string_view::npos ||
          !parse_number(f.first.data(), f.first.data() + f.first.size(), v) || !(v > previous))
        return false;
      previous = v;
      ++seen;
    }
    return seen > 0;
  }

  // The first data line: fixes the number of fields and the column.
  void fix_layout(const Fields& f, std::string_view text_line, std::size_t next_line) {
    fields = f.count;
    first_data_line = line;
    if (column_asked > 0) {
      column = column_asked;
      return;
    }
    if (f.count == 1) {
      column = 1;
      return;
    }
    if (f.bare_comma && !f.other_separator && !f.point)
      throw DataFileError(quoted(text_line) +
                              ": ',' may be a decimal comma or a column separator: write decimal "
                              "points, or give --column",
                          line);
    if (f.count == 2 && first_column_increases(f.first, next_line)) {
      column = 2;
      note = "column 2 (column 1 increases from line to line: time stamps; --column chooses another)";
      return;
    }
    throw DataFileError("has " + std::to_string(f.count) + " columns: give the one to analyze with --column (1 to " +
                            std::to_string(f.count) + ")",
                        line);
  }

  // A complete line (without its '\n'): a value, or nothing (blank, comment). Throws on a line
  // that breaks the rules.
  bool parse_line(std::string_view text_line, std::size_t next_line, double& value) {
    ++line;
    if (line == 1 && text_line.substr(0, 3) == "\xEF\xBB\xBF") text_line.remove_prefix(3);  // UTF-8 mark
    Fields f = split(text_line, fields == 0 ? std::max(column_asked, 1u) : column);
    if (f.binary_at != std::string_view::npos)
      throw DataFileError("not text: byte " + quoted(text_line.substr(f.binary_at, 1)) + " at column " +
                              std::to_string(f.binary_at + 1) + " (a binary file?)",
                          line);
    if (f.count == 0) {
      if (!values_seen && !text_line.empty() && text_line[0] == '#' && header.size() < max_header_lines) {
        while (!text_line.empty() && text_line.back() == '\r') text_line.remove_suffix(1);
        header.emplace_back(text_line);
      }
      return false;
    }
    if (f.bare_comma && f.other_separator)
      throw DataFileError(quoted(text_line) + ": a decimal comma? write decimal points", line);
    if (fields == 0) {
      fix_layout(f, text_line, next_line);
      f = split(text_line, column);
    }
    if (f.count != fields)
      throw DataFileError("has " + std::to_string(f.count) + " field(s) where line " + std::to_string(first_data_line) +
                              " has " + std::to_string(fields) +
                              (f.bare_comma ? " (a decimal comma? write decimal points)" : ""),
                          line);
    if (f.count < column)
      throw DataFileError("line has " + std::to_string(f.count) + " column(s), column " + std::to_string(column) +
                              " was asked for",
                          line);
    if (!parse_number(f.chosen.data(), f.chosen.data() + f.chosen.size(), value))
      throw DataFileError("not a finite number in column " + std::to_string(column) + ": " + quoted(f.chosen), line);
    values_seen = true;
    return true;
  }
};

DataFile::DataFile(const std::string& path, unsigned column) : impl_(std::make_unique<Impl>()) {
  impl_->column_asked = column;
  impl_->source.open(path);
  impl_->end = impl_->source.start(impl_->text.get(), text_capacity);
  impl_->text[impl_->end] = '\n';
  impl_->at_end = impl_->end == 0;
}

DataFile::~DataFile() = default;

std::size_t DataFile::read(std::span<double> out) {
  Impl& f = *impl_;
  if (f.lines.size() < out.size()) f.lines.resize(out.size());
  char* const text = f.text.get();
  std::size_t k = 0;
  while (k < out.size()) {
    // Fast path, once the file is known to hold one number per line: [+-]digits or what
    // from_chars reads, then '\n' or "\r\n". The '\n' after the text stops every scan.
    if (f.fields == 1) {
      while (k < out.size()) {
        const char* p = text + f.begin;
        const char* const end = text + f.end;
        const char* q = p;
        const bool negative = *q == '-';
        if (*q == '-' || *q == '+') ++q;
        const char* digits = q;
        std::uint64_t v = 0;
        while (is_digit(*q)) v = v * 10 + static_cast<unsigned>(*q++ - '0');
        double value = 0;
        if (q > digits && q - digits <= 18 && (*q == '\n' || *q == '\r')) {
          value = negative ? -static_cast<double>(v) : static_cast<double>(v);
        } else if (q > digits && (*q == '.' || *q == 'e' || *q == 'E')) {
          const auto [ptr, ec] = std::from_chars(p + (*p == '+'), end, value);
          if (ec != std::errc() || !std::isfinite(value)) break;
          q = ptr;
        } else {
          break;
        }
        if (*q == '\r') ++q;
        if (*q != '\n' || q >= end) break;
        out[k] = value;
        f.lines[k++] = ++f.line;
        f.begin = static_cast<std::size_t>(q + 1 - text);
      }
      if (k == out.size()) break;
    }
    // Any other line, one at a time.
    const char* p = text + f.begin;
    const char* nl = static_cast<const char*>(std::memchr(p, '\n', f.end - f.begin));
    std::size_t stop = 0;
    if (nl != nullptr) {
      stop = static_cast<std::size_t>(nl - text);
    } else if (f.refill()) {
      continue;
    } else if (f.begin < f.end) {
      stop = f.end;  // the last line has no '\n'
    } else {
      break;
    }
    const std::string_view line(text + f.begin, stop - f.begin);
    f.begin = std::min(stop + 1, f.end);
    if (f.parse_line(line, f.begin, out[k])) f.lines[k++] = f.line;
  }
  return k;
}

std::uint64_t DataFile::line_of(std::size_t i) const { return impl_->lines[i]; }
unsigned DataFile::column() const { return impl_->column; }
const std::string& DataFile::layout_note() const { return impl_->note; }
const std::vector<std::string>& DataFile::header() const { return impl_->header; }
std::uint64_t DataFile::values_bound() const {
  const std::uint64_t bytes = impl_->source.text_size_hint();
  return bytes == 0 ? 0 : bytes / 2 + 1;
}
std::uint64_t DataFile::bytes_read() const { return impl_->source.consumed(); }
std::uint64_t DataFile::size_bytes() const { return impl_->source.size(); }

}  // namespace gyrochar
