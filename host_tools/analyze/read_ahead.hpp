#pragma once
// A data file read on a thread of its own, a few blocks ahead of the pass that uses the values:
// parsing the text overlaps what the pass does with each block (on a long file each is about half
// of the read pass's time; BENCHMARKS.md, "The bias ratio a span at a time, the read pass on two
// threads").
//
// Only the reading thread touches the DataFile while a ReadAhead lives. The blocks come in the
// file's order, each with the lines of its values and the bytes read when it was read; an error
// of the file (DataFileError, or any other exception of its read()) comes after every block read
// before it, as the file's own read() would have given them.
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

#include "datafile.hpp"

namespace gyrochar {

class ReadAhead {
 public:
  /// Starts reading `file` in blocks of `block` values (block >= 1), at most `depth` (>= 2) blocks
  /// held at once. Allocates depth * block values and lines.
  ReadAhead(DataFile& file, std::size_t block, std::size_t depth = 4);
  /// Stops the reading thread (after the read() it may be in) and waits for it.
  ~ReadAhead();
  ReadAhead(const ReadAhead&) = delete;
  ReadAhead& operator=(const ReadAhead&) = delete;

  /// The next block of values, valid until the next call; empty at the end of the data. Throws
  /// what the file's read() threw, once every block before it has been returned.
  std::span<double> next();
  /// Line of value i of the block next() returned last, and the file's bytes_read() after it.
  std::uint64_t line_of(std::size_t i) const { return ring_[head_].lines[i]; }
  std::uint64_t bytes_read() const { return ring_[head_].bytes; }

 private:
  struct Block {
    std::vector<double> values;
    std::vector<std::uint64_t> lines;
    std::size_t n = 0;
    std::uint64_t bytes = 0;
  };
  void read(std::stop_token stop);

  DataFile& file_;
  std::vector<Block> ring_;
  std::mutex mutex_;
  std::condition_variable_any changed_;
  std::size_t head_ = 0, filled_ = 0;  // ring_[head_] first of the filled_ blocks read and not given back
  bool held_ = false;                  // next() has returned ring_[head_] and the caller may read it
  bool ended_ = false;                 // the thread read the end of the data, or an error
  std::exception_ptr error_;
  std::jthread thread_;  // last: started once the rest is in place
};

}  // namespace gyrochar
