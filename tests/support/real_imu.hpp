// The real gyro records (six ADIS16405 runs, README beside them) are not part of the project: their
// licence, CC BY-NC-SA 4.0, does not allow it. They are read from GYROCHAR_REAL_IMU (a CMake cache
// path, by default ../shared/refdata/real-imu beside the checkout); the tests that need them skip,
// saying why, where the folder is absent.
#pragma once

#include <fstream>
#include <string>

namespace gyrochar::test {

inline std::string real_imu_record(const std::string& name) { return std::string(GYROCHAR_REAL_IMU) + "/" + name; }

// Empty when the record can be read, else the reason its test skips.
inline std::string real_imu_absent(const std::string& path) {
  if (std::ifstream(path)) return {};
  return path +
         " cannot be read: the ADIS16405 records (CC BY-NC-SA 4.0) are not part of the project; "
         "configure with -DGYROCHAR_REAL_IMU=<their folder> to run this test";
}

}  // namespace gyrochar::test
