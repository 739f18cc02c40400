// The data file reader: what it reads, and that it never misreads. Oracles: the values written
// into each file by the test itself (exact: integers and short decimals round-trip through
// from_chars), and the reader's documented rules (datafile.hpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "datafile.hpp"
#include "read_ahead.hpp"
#include "support/shell.hpp"

namespace {

using gyrochar::DataFile;
using gyrochar::DataFileError;
using gyrochar::ReadAhead;

std::string file_with(const std::string& name, const std::string& content) {
  const std::string path = gyrochar::test_support::temp_path(name);
  std::ofstream(path, std::ios::binary) << content;
  return path;
}

std::vector<double> read_all(const std::string& path, unsigned column = 0, std::size_t block = 5) {
  DataFile file(path, column);
  std::vector<double> values, out(block);
  while (const std::size_t n = file.read(out)) values.insert(values.end(), out.begin(), out.begin() + n);
  return values;
}

// The error of reading `content`, or "" when it reads.
std::string error_of(const std::string& content, unsigned column = 0) {
  try {
    read_all(file_with("bad.txt", content), column);
  } catch (const DataFileError& e) {
    return "line " + std::to_string(e.line()) + ": " + e.what();
  }
  return "";
}

TEST(DataFile, OneNumberPerLineInEveryNotation) {
  const auto v = read_all(file_with("plain.txt", "# header\n12\n-3\n+4\n\n  5  \n1.5\n-2.5e-3\r\n7 # comment\n1e3\n8"));
  EXPECT_EQ(v, (std::vector<double>{12, -3, 4, 5, 1.5, -2.5e-3, 7, 1e3, 8}));
}

TEST(DataFile, PercentStartsACommentAsHashDoes) {
  // SigmaTheta's .ykt files begin with '%' lines; MATLAB writes them too.
  const auto v = read_all(
      file_with("ykt.txt", "% SigmaTheta\n%  tau0 = 1 s\n1.5e-12\n  % indented\n-2e-12 % after\n3e-12\n"));
  EXPECT_EQ(v, (std::vector<double>{1.5e-12, -2e-12, 3e-12}));
  EXPECT_EQ(read_all(file_with("ykt2.txt", "% t y\n0 1.5\n1 2.5 % late\n2 3.5\n")), (std::vector<double>{1.5, 2.5, 3.5}));
}

TEST(DataFile, LinesAndHeaderOfEachValue) {
  DataFile file(file_with("lines.txt", "# one\n#two\n\n10\n# later\n20\n"));
  double v[4];
  ASSERT_EQ(file.read(v), 2u);
  EXPECT_EQ(file.line_of(0), 4u);
  EXPECT_EQ(file.line_of(1), 6u);
  EXPECT_EQ(file.header(), (std::vector<std::string>{"# one", "#two"}));  // before the first value only
  EXPECT_EQ(file.column(), 1u);
}

TEST(DataFile, BlocksAcrossTheBufferGiveTheSameValues) {
  // 400 000 lines (2.6 MB) cross the 1 MiB buffer several times; block sizes 1, 7 and 4096.
  std::string s;
  std::vector<double> want;
  for (int i = 0; i < 400000; ++i) {
    const int v = static_cast<int>(std::int64_t{i} * 7919 % 200001) - 100000;
    s += std::to_string(v) + (i % 3 ? "\n" : "\r\n");
    want.push_back(v);
  }
  const std::string path = file_with("long.txt", s);
  for (const std::size_t block : {std::size_t{1}, std::size_t{7}, std::size_t{4096}})
    EXPECT_EQ(read_all(path, 0, block), want);
  ASSERT_EQ(std::system(("gzip -kf " + path).c_str()), 0);
  EXPECT_EQ(read_all(path + ".gz", 0, 4096), want);
  // Two gzip members, as `cat a.gz b.gz` makes: both are read.
  ASSERT_EQ(std::system(("cat " + path + ".gz " + path + ".gz > " + path + ".twice.gz").c_str()), 0);
  std::vector<double> twice = want;
  twice.insert(twice.end(), want.begin(), want.end());
  EXPECT_EQ(read_all(path + ".twice.gz", 0, 4096), twice);
}

TEST(DataFile, ColumnsOfATable) {
  const std::string csv = file_with("table.csv", "# t, a, b\n0.0, 10, 100\n0.5,11,101\n1.0 ; 12 ; 102\n");
  EXPECT_EQ(read_all(csv, 2), (std::vector<double>{10, 11, 12}));
  EXPECT_EQ(read_all(csv, 3), (std::vector<double>{100, 101, 102}));
  EXPECT_EQ(read_all(file_with("blanks.txt", "1\t2\n3   4\n"), 2), (std::vector<double>{2, 4}));
  // An explicit column makes a table of bare commas a table (integer time, count).
  EXPECT_EQ(read_all(file_with("ints.csv", "12,1000\n13,1001\n"), 2), (std::vector<double>{1000, 1001}));
}

TEST(DataFile, TimeStampColumnIsChosenAndSaid) {
  std::vector<double> v(8);
  EXPECT_NE(error_of("time,value\n0.00,5\n0.01,-6\n0.02,7\n"), "");  // the title line is not a number
  DataFile plain(file_with("tv2.csv", "# time,value\n0.00,5\n0.01,-6\n0.02,7\n"), 0);
  ASSERT_EQ(plain.read(v), 3u);
  EXPECT_EQ(std::vector<double>(v.begin(), v.begin() + 3), (std::vector<double>{5, -6, 7}));
  EXPECT_EQ(plain.column(), 2u);
  EXPECT_NE(plain.layout_note().find("column 2"), std::string::npos) << plain.layout_note();
  // A first column that does not increase, or three columns: the reader does not guess.
  EXPECT_NE(error_of("5 1\n4 2\n6 3\n").find("--column"), std::string::npos);
  EXPECT_NE(error_of("1 2 3\n2 3 4\n").find("--column"), std::string::npos);
  EXPECT_NE(error_of("1 2\n").find("--column"), std::string::npos);  // one line shows no trend
}

TEST(DataFile, DecimalCommasAreNeverHalfRead) {
  // One value per line with decimal commas: "1,288185" is neither 1 nor two columns.
  EXPECT_NE(error_of("1,288185\n1,288190\n1,288195\n").find("decimal comma"), std::string::npos);
  EXPECT_NE(error_of("1,5\n2,5\n3,5\n").find("decimal comma"), std::string::npos);  // increasing too
  // Beside another separator a comma between digits is a decimal comma, whatever the column.
  EXPECT_NE(error_of("0,001;1,5\n0,002;1,6\n", 2).find("decimal comma"), std::string::npos);
  EXPECT_NE(error_of("0,001 1,5\n", 2).find("decimal comma"), std::string::npos);
  // One decimal comma among plain numbers: the field count tells, and the message says why.
  const std::string e = error_of("1.5\n2.5\n3,5\n4.5\n");
  EXPECT_EQ(e.rfind("line 3: ", 0), 0u) << e;
  EXPECT_NE(e.find("decimal comma"), std::string::npos) << e;
}

TEST(DataFile, ANulByteNeverJoinsTwoLines) {
  // printf '1\n2\n3\0\n4\n5\n6\n': neither 34 nor a silent 3.
  const std::string e = error_of(std::string("1\n2\n3\0\n4\n5\n6\n", 13));
  EXPECT_EQ(e.rfind("line 3: ", 0), 0u) << e;
  EXPECT_NE(e.find("\\x00"), std::string::npos) << e;  // named, not echoed
}

TEST(DataFile, BinaryBytesAreNeverEchoed) {
  std::string bytes;
  for (int i = 0; i < 4096; ++i) bytes += static_cast<char>((i * 167 + 13) % 256);
  for (const std::string& content : {bytes, "\x89PNG\r\n\x1a\n" + bytes, "1\n2\n\xff\xfe" + bytes}) {
    const std::string e = error_of(content);
    ASSERT_NE(e, "");
    for (const char c : e)
      EXPECT_TRUE(c >= 0x20 && c < 0x7f) << "raw byte " << int(static_cast<unsigned char>(c)) << " in: " << e;
    EXPECT_LT(e.size(), 200u) << e;
  }
}

TEST(DataFile, RaggedTablesAndBadNumbersAreRefused) {
  EXPECT_NE(error_of("1 2\n3\n", 1).find("line 2"), std::string::npos);
  EXPECT_NE(error_of("1 2\n3 4 5\n", 1).find("line 2"), std::string::npos);
  EXPECT_NE(error_of("1 2\n3 4\n", 3).find("column 3"), std::string::npos);
  EXPECT_NE(error_of("1\n0x10\n").find("not a finite number"), std::string::npos);
  EXPECT_NE(error_of("1\ninf\n").find("not a finite number"), std::string::npos);
  EXPECT_NE(error_of("1\n2.5.1\n").find("line 2"), std::string::npos);
  EXPECT_NE(error_of("1,,2\n", 2).find("column 2"), std::string::npos);           // an empty field is no number
  EXPECT_NE(error_of(std::string(2 << 20, '7')).find("MiB"), std::string::npos);  // no line end at all
}

TEST(DataFile, GzipCutShortOrCorruptIsAnError) {
  std::string s;
  for (int i = 0; i < 50000; ++i) s += std::to_string(i) + "\n";
  const std::string path = file_with("cut.txt", s);
  ASSERT_EQ(std::system(("gzip -kf " + path + " && head -c 20000 " + path + ".gz > " + path + ".cut.gz").c_str()), 0);
  EXPECT_THROW(read_all(path + ".cut.gz"), DataFileError);
  try {
    read_all(path + ".cut.gz");
  } catch (const DataFileError& e) {
    EXPECT_NE(std::string(e.what()).find("unexpected end of file"), std::string::npos) << e.what();
  }
  ASSERT_EQ(std::system(("cp " + path + ".gz " + path + ".bad.gz && printf 'XXXXXXXX' | dd of=" + path +
                         ".bad.gz bs=1 seek=5000 conv=notrunc 2>/dev/null")
                            .c_str()),
            0);
  EXPECT_THROW(read_all(path + ".bad.gz"), DataFileError);
  ASSERT_EQ(std::system(("cp " + path + ".gz " + path + ".tail.gz && printf 'junk' >> " + path + ".tail.gz").c_str()), 0);
  EXPECT_THROW(read_all(path + ".tail.gz"), DataFileError);
}

TEST(DataFile, ValuesBoundFromTheFileLength) {
  DataFile file(file_with("bound.txt", "1\n22\n333\n"));  // 9 bytes: at most 5 values of 2 bytes
  EXPECT_EQ(file.values_bound(), 5u);
  EXPECT_EQ(file.size_bytes(), 9u);
}

}  // namespace

// ReadAhead: the oracle is the DataFile read in turn, block by block, on the same file.
namespace {

std::string long_file(std::size_t values, std::size_t bad_at = 0) {
  std::string text = "# a header\n";
  for (std::size_t i = 1; i <= values; ++i) {
    if (i % 97 == 0) text += "\n# a comment\n";
    text += i == bad_at ? "1.5x\n" : std::to_string(i) + "." + std::to_string(i % 7) + "\n";
  }
  return text;
}

struct Read {
  std::vector<double> values;
  std::vector<std::uint64_t> lines;
};

Read ahead_of(const std::string& path, std::size_t block, std::size_t depth) {
  DataFile file(path);
  ReadAhead ahead(file, block, depth);
  Read r;
  for (std::span<double> v; !(v = ahead.next()).empty();) {
    EXPECT_LE(v.size(), block);
    for (std::size_t i = 0; i < v.size(); ++i) r.values.push_back(v[i]), r.lines.push_back(ahead.line_of(i));
  }
  EXPECT_TRUE(ahead.next().empty());  // the end stays the end
  return r;
}

}  // namespace

TEST(ReadAhead, TheSameValuesAndLinesAsTheFileInTurn) {
  const std::string path = file_with("ahead.txt", long_file(50000));
  Read want;
  {
    DataFile file(path);
    std::vector<double> out(1000);
    while (const std::size_t n = file.read(out))
      for (std::size_t i = 0; i < n; ++i) want.values.push_back(out[i]), want.lines.push_back(file.line_of(i));
  }
  ASSERT_EQ(want.values.size(), 50000u);
  for (const auto& [block, depth] : {std::pair<std::size_t, std::size_t>{7, 2}, {1000, 4}, {1 << 14, 3}, {100000, 2}}) {
    const Read got = ahead_of(path, block, depth);
    EXPECT_EQ(got.values, want.values) << block << " " << depth;
    EXPECT_EQ(got.lines, want.lines) << block << " " << depth;
  }
  EXPECT_TRUE(ahead_of(file_with("empty.txt", "# nothing\n\n"), 16, 2).values.empty());
}

TEST(ReadAhead, AnErrorComesAfterEveryBlockBeforeIt) {
  // Value 30001 is on line 1 + 30001 + 2 * floor(30001 / 97) (the header, the values, each
  // comment's blank line and its own line): the error names it, after the blocks before its own.
  const std::string path = file_with("ahead_bad.txt", long_file(40000, 30001));
  DataFile file(path);
  ReadAhead ahead(file, 1000, 4);
  std::size_t values = 0;
  std::uint64_t line = 0;
  try {
    for (std::span<double> v; !(v = ahead.next()).empty();) values += v.size();
    ADD_FAILURE() << "no error";
  } catch (const DataFileError& e) {
    line = e.line();
  }
  EXPECT_EQ(values, 30000u);  // the blocks of 1000 before the failing one
  EXPECT_EQ(line, 1u + 30001u + 2u * (30001u / 97u));
  EXPECT_THROW(ahead.next(), DataFileError);  // and again
}

TEST(ReadAhead, StopsWhenLeftEarly) {
  // The reading thread waits for room after `depth` blocks: leaving after one must end it.
  const std::string path = file_with("ahead_early.txt", long_file(200000));
  for (int round = 0; round < 20; ++round) {
    DataFile file(path);
    ReadAhead ahead(file, 512, 2);
    ASSERT_EQ(ahead.next().size(), 512u);
  }
}
