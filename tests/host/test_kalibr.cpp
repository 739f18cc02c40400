// The Kalibr imu.yaml (common/kalibr.hpp) from a fit and from a decoded node. Oracle: the closed
// forms of the conversion, computed by hand: N = 0.003 deg/sqrt(h) = 0.003 x (pi/180) rad / 60 s^0.5
// = 8.726646259971648e-07 rad/s/sqrt(Hz); K = 0.01 deg/h/sqrt(h) = 0.01 x (pi/180) / 3600 / 60
// = 8.080228018492267e-10 rad/s^2/sqrt(Hz); a node in arcsec: N = 10.8 arcsec/sqrt(s) =
// 10.8 x pi / 648000 = 5.235987755982989e-05, K = 0.36 arcsec/s^1.5 = 1.7453292519943296e-06.
#include <gtest/gtest.h>

#include <map>
#include <sstream>
#include <string>

#include "display_units.hpp"
#include "kalibr.hpp"

namespace gyrochar {
namespace {

// The keys of a YAML file of `key: value  # comment` lines ('#' lines skipped).
std::map<std::string, std::string> yaml_keys(const std::string& text) {
  std::map<std::string, std::string> keys;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    const auto colon = line.find(':');
    std::string value = line.substr(colon + 1, line.find('#') - colon - 1);
    value.erase(0, value.find_first_not_of(' '));
    value.erase(value.find_last_not_of(' ') + 1);
    keys[line.substr(0, colon)] = value;
  }
  return keys;
}

void expect_rel(double got, double want, double rel) { EXPECT_NEAR(got, want, rel * want) << got << " vs " << want; }

TEST(Kalibr, NoiseDensityIsNAndRandomWalkIsKInSI) {
  const double n = 8.726646259971648e-07, k = 8.080228018492267e-10;  // the header's hand-computed values
  std::string why;
  const auto yaml = kalibr_imu_yaml({n, 0.02, true, true}, {k, 0.3, true, false}, 100.0, "test", why);
  ASSERT_TRUE(yaml) << why;
  auto keys = yaml_keys(*yaml);
  EXPECT_EQ(std::stod(keys.at("gyroscope_noise_density")), n);  // shortest round-trip text: exact
  EXPECT_EQ(std::stod(keys.at("gyroscope_random_walk")), k);
  EXPECT_EQ(keys.at("update_rate"), "100");
  EXPECT_EQ(keys.at("rostopic"), "/imu0");
  EXPECT_EQ(keys.count("accelerometer_noise_density"), 0u);  // not measured: left to the user, commented
  EXPECT_NE(yaml->find("#accelerometer_noise_density:"), std::string::npos);
  // The comments give the terms back in gyro units.
  EXPECT_NE(yaml->find("N = 0.003 deg/sqrt(h)"), std::string::npos) << *yaml;
  EXPECT_NE(yaml->find("K = 0.01 deg/h/sqrt(h)"), std::string::npos) << *yaml;
  EXPECT_NE(yaml->find("not resolved"), std::string::npos);  // K above
}

TEST(Kalibr, RefusesWhatKalibrCannotTake) {
  std::string why;
  EXPECT_FALSE(kalibr_imu_yaml({1e-6, 0, true, true}, {1e-9, 0, false, false}, 100, "t", why));
  EXPECT_EQ(why, "K (rate random walk) is not in the fitted model: Kalibr needs it > 0");
  EXPECT_FALSE(kalibr_imu_yaml({0, 0, true, true}, {1e-9, 0, true, true}, 100, "t", why));
  EXPECT_EQ(why.rfind("N (angle random walk) = 0 is not a positive number", 0), 0u) << why;
  EXPECT_FALSE(kalibr_imu_yaml({1e-6, 0, true, true}, {1e-9, 0, true, true}, 0, "t", why));
  EXPECT_EQ(why, "the sample rate (1 / tau0) is not known");
}

TEST(Kalibr, PartialLeavesATermTheFitLeftOutToFillIn) {
  // The analyzer's file when K is not in the model: N as always, K's key commented out with '?'
  // as the accelerometer keys are (Kalibr refuses the file until it is filled in), and a note.
  std::string why;
  const double n = 8.726646259971648e-07;  // the header's hand-computed value
  const auto yaml = kalibr_imu_yaml({n, 0.02, true, true}, {0, 0, false, false}, 100.0, "t", why, true);
  ASSERT_TRUE(yaml) << why;
  EXPECT_EQ(why,
            "K (rate random walk) is not in the fitted model: its key is written commented out with '?' for you to "
            "fill in (Kalibr needs it > 0)");
  const auto keys = yaml_keys(*yaml);
  EXPECT_EQ(std::stod(keys.at("gyroscope_noise_density")), n);
  EXPECT_EQ(keys.count("gyroscope_random_walk"), 0u);
  EXPECT_NE(yaml->find("\n#gyroscope_random_walk: ?   # rad/s^2/sqrt(Hz); K is not in the fitted model"), std::string::npos)
      << *yaml;
  // Neither term: nothing to give, refused as without `partial`; a bad N still refused.
  EXPECT_FALSE(kalibr_imu_yaml({0, 0, false, false}, {0, 0, false, false}, 100, "t", why, true));
  EXPECT_EQ(why, "N (angle random walk) is not in the fitted model: Kalibr needs it > 0");
  EXPECT_FALSE(kalibr_imu_yaml({-1, 0, true, true}, {0, 0, false, false}, 100, "t", why, true));
  EXPECT_EQ(why.rfind("N (angle random walk) = -1 is not a positive number", 0), 0u) << why;
}

NodeView node_in(protocol::AngleUnit unit) {
  using namespace protocol;
  NodeView v;
  v.address = 0x10;
  v.scale = MetaScaleMsg{0, 1.0f, unit, InputSource::simulated};
  v.sampling = MetaSamplingMsg{0, 0.01f, 8};
  v.ieee952[1] = {true, true, 10.8f, 0.05f, true};  // N, arcsec/sqrt(s)
  v.ieee952[3] = {true, false, 0.36f, 0.4f, true};  // K, arcsec/s^1.5
  v.ieee952_summary = Ieee952SummaryMsg{0, Ieee952Status::ok, 1.0f, 20, true, {0, 0}};
  return v;
}

TEST(Kalibr, ADecodedNodeIsConvertedFromItsAngleUnit) {
  std::string why;
  const auto yaml = decoding::kalibr_yaml(node_in(protocol::AngleUnit::arcsec), why);
  ASSERT_TRUE(yaml) << why;
  const auto keys = yaml_keys(*yaml);
  // The wire's float32 values (10.8f, 0.36f) are within 4e-8 of the decimal ones.
  expect_rel(std::stod(keys.at("gyroscope_noise_density")), 5.235987755982989e-05, 1e-7);
  expect_rel(std::stod(keys.at("gyroscope_random_walk")), 1.7453292519943296e-06, 1e-7);
  EXPECT_EQ(keys.at("update_rate"), "100");  // 1 / 0.01f in float32

  EXPECT_FALSE(decoding::kalibr_yaml(node_in(protocol::AngleUnit::pulse), why));
  EXPECT_EQ(why, "the node reports pulses: no angle to give Kalibr");
  NodeView rejected = node_in(protocol::AngleUnit::arcsec);
  rejected.ieee952_summary->status = protocol::Ieee952Status::rejected;
  EXPECT_FALSE(decoding::kalibr_yaml(rejected, why));
  EXPECT_EQ(why, "the node's IEEE-952 fit is rejected: no noise parameters to give");
}

}  // namespace
}  // namespace gyrochar
