// Loads a world file of tests/worlds by name (test helper).
#ifndef IRSLAM_TESTS_TESTING_WORLDS_H_
#define IRSLAM_TESTS_TESTING_WORLDS_H_

#include <gtest/gtest.h>

#include <string>

#include "sim/world.h"

namespace irslam::testing {

inline sim::World LoadTestWorld(const std::string& name) {
  std::string error;
  auto w = sim::LoadWorldFile(std::string(IRSLAM_SOURCE_DIR) + "/tests/worlds/" + name + ".json", &error);
  EXPECT_TRUE(w) << error;
  return w.value_or(sim::World{});
}

}  // namespace irslam::testing

#endif  // IRSLAM_TESTS_TESTING_WORLDS_H_
