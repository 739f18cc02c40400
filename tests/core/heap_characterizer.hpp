#pragma once
// A counts characterizer on heap storage for any stride factor, and its exact sums as the
// oracle's 128-bit integers: what the block kernel and batch tests compare against.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "gyrochar/characterizer.hpp"
#include "oracle/brute_force.hpp"

namespace gyrochar {

inline oracle::u128 to_u128(UInt128 v) { return (oracle::u128{v.hi} << 64) | v.lo; }

struct Heap {
  std::vector<CountArith::Entry> history;
  std::vector<Characterizer<CountArith>::TauState> taus;
  Characterizer<CountArith> c;
  Heap(std::uint32_t s, const std::vector<std::uint64_t>& m_list)
      : history(history_entries(s, m_list.back())), taus(m_list.size()), c(history, taus) {
    EXPECT_EQ(c.configure({s, 0}, m_list), ConfigureStatus::ok);
  }
};

}  // namespace gyrochar
