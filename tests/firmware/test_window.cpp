// The board's dynamic Allan deviation (firmware/window.hpp): each window's curve is that of its
// samples cut out of the run, gaps break a window as they break the run, the window taus stop at a
// quarter of the window, and the window survives a checkpoint.
// Oracles: a characterizer fed one window's counts directly (the same exact integer sums, so the
// same variances to the last bit), and the checkpoint format's checks.
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <vector>

#include "window.hpp"

namespace gyrochar::firmware {
namespace {

std::vector<std::int32_t> counts(std::size_t n, std::uint64_t seed = 11) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 4.0);
  std::vector<std::int32_t> c(n);
  for (auto& v : c) v = 7 + static_cast<std::int32_t>(std::lround(noise(rng)));
  return c;
}

/// The oracle: octave taus 1 .. 2^(taus-1), fed [begin, end) of `c`, with a gap before the
/// samples listed in `gaps_before`.
std::unique_ptr<WindowPyramid> direct(const std::vector<std::int32_t>& c, std::size_t begin, std::size_t end, unsigned taus,
                                      const std::vector<std::size_t>& gaps_before = {}) {
  auto p = std::make_unique<WindowPyramid>();
  std::vector<std::uint64_t> m;
  for (unsigned k = 0; k < taus; ++k) m.push_back(std::uint64_t{1} << k);
  EXPECT_EQ(p->configure({8, 0}, m), ConfigureStatus::ok);
  for (std::size_t k = begin; k < end; ++k) {
    for (const std::size_t g : gaps_before)
      if (g == k) p->mark_gap();
    p->add_increment(c[k]);
  }
  return p;
}

constexpr std::uint64_t length = 1000;  // samples per window in these tests: 8 window taus
const unsigned taus = window_taus(32, length);

/// A window of `length` samples over `taus` taus, S = 8, checkpoint tag `tag`.
std::unique_ptr<DynamicWindow> window(std::uint32_t tag = 0) {
  auto w = std::make_unique<DynamicWindow>();
  EXPECT_TRUE(w->configure(8, tag, taus, length));
  return w;
}

void expect_curve(const WindowCurve& w, const WindowPyramid& oracle) {
  ASSERT_TRUE(w.complete);
  for (std::size_t i = 0; i < oracle.tau_count(); ++i) {
    const auto r = oracle.result(i);
    EXPECT_EQ(w.avar[i], variance(r, SumKind::avar, 1.0)) << "tau " << i;
    EXPECT_EQ(w.mvar[i], variance(r, SumKind::mvar, 1.0)) << "tau " << i;
    EXPECT_TRUE(w.valid[i]) << "tau " << i;
  }
}

TEST(Window, TausReachAQuarterOfTheWindow) {
  EXPECT_EQ(window_taus(32, 3), 0u);
  EXPECT_EQ(window_taus(32, 4), 1u);     // m = 1: 4 m <= 4
  EXPECT_EQ(window_taus(32, 1000), 8u);  // m = 128: 512 <= 1000 < 1024
  EXPECT_EQ(window_taus(32, 1024), 9u);
  EXPECT_EQ(window_taus(5, 1000000), 5u);                               // no more than the node's taus
  EXPECT_EQ(window_taus(40, std::uint64_t{1} << 39), max_window_taus);  // nor than the capacity
}

TEST(Window, EachWindowIsItsSamplesCutOutIntoARunOfTheirOwn) {
  const auto c = counts(3500);
  auto w = window();
  EXPECT_FALSE(w->latest().complete);
  for (std::size_t k = 0; k < c.size(); ++k) {
    w->add(c[k]);
    if ((k + 1) % length != 0) continue;
    const std::size_t window = k / length;
    EXPECT_EQ(w->latest().window, window);
    EXPECT_EQ(w->latest().gaps, 0u);
    expect_curve(w->latest(), *direct(c, window * length, (window + 1) * length, taus));
    EXPECT_EQ(w->samples_in_window(), 0u);
  }
  EXPECT_EQ(w->latest().window, 2u) << "the half window at the end is not complete";
  EXPECT_EQ(w->samples_in_window(), 500u);
}

TEST(Window, AGapBreaksTheWindowAsItBreaksTheRun) {
  const auto c = counts(2000, 5);
  auto w = window();
  for (std::size_t k = 0; k < c.size(); ++k) {
    if (k == 1300) w->mark_gap();
    w->add(c[k]);
  }
  EXPECT_EQ(w->latest().window, 1u);
  EXPECT_EQ(w->latest().gaps, 1u);
  expect_curve(w->latest(), *direct(c, 1000, 2000, taus, {1300}));
}

TEST(Window, ConfigurationsBeyondItsCapacityAreRefused) {
  auto w = std::make_unique<DynamicWindow>();
  EXPECT_FALSE(w->configure(8, 0, 0, 1000));
  EXPECT_FALSE(w->configure(8, 0, max_window_taus + 1, std::uint64_t{1} << 40));
  EXPECT_FALSE(w->configure(8, 0, 9, 1000)) << "m = 256 needs 1024 samples";
  EXPECT_FALSE(w->configure(128, 0, 4, 1000)) << "stride factor beyond the pyramid's";
  EXPECT_TRUE(w->configure(8, 0, 8, 1000));
  // A window whose configure() failed restores nothing (it has no length to check samples against).
  std::vector<std::byte> bytes(w->checkpoint_size());
  ASSERT_EQ(w->save(bytes), bytes.size());
  EXPECT_FALSE(w->configure(8, 0, 0, 1000));
  EXPECT_EQ(w->restore(bytes), RestoreStatus::config_mismatch);
}

TEST(Window, ACheckpointCarriesTheWindowOnAfterAGap) {
  const auto c = counts(2500, 9);
  auto a = window(77);
  for (std::size_t k = 0; k < 1600; ++k) a->add(c[k]);
  std::vector<std::byte> bytes(a->checkpoint_size());
  ASSERT_EQ(a->save(bytes), bytes.size());

  auto b = window(77);
  ASSERT_EQ(b->restore(bytes), RestoreStatus::ok);
  EXPECT_EQ(b->latest().window, 0u);
  expect_curve(b->latest(), *direct(c, 0, 1000, taus));
  for (std::size_t k = 1600; k < c.size(); ++k) b->add(c[k]);
  EXPECT_EQ(b->latest().window, 1u);
  EXPECT_EQ(b->latest().gaps, 1u) << "the restart is a gap";
  expect_curve(b->latest(), *direct(c, 1000, 2000, taus, {1600}));

  // Refused, and nothing changes: truncated, corrupted (in either part), another tag.
  EXPECT_EQ(window(77)->restore(std::span(bytes).first(bytes.size() - 1)), RestoreStatus::truncated);
  for (const std::size_t where : {std::size_t{100}, bytes.size() - 8}) {
    std::vector<std::byte> bad = bytes;
    bad[where] ^= std::byte{0x40};
    auto w = window(77);
    EXPECT_EQ(w->restore(bad), RestoreStatus::corrupted) << where;
    EXPECT_FALSE(w->latest().complete);
    EXPECT_EQ(w->samples_in_window(), 0u);
  }
  EXPECT_EQ(window(78)->restore(bytes), RestoreStatus::config_mismatch);
}

}  // namespace
}  // namespace gyrochar::firmware
