// irslam-report --mode clean: cleaning over the paper's worlds and generated
// worlds, scored against the truth (clean_eval.h), with the random-bounce
// baseline; writes cleaning-results.md and cleaning-coverage.svg.
#ifndef IRSLAM_TESTS_TOOLS_CLEAN_REPORT_H_
#define IRSLAM_TESTS_TOOLS_CLEAN_REPORT_H_

#include <string>
#include <vector>

#include "robot/robot_core.h"

namespace irslam::report {

int RunCleanReport(const robot::CoreOptions& options, const std::string& worlds_dir,
                   const std::vector<std::string>& worlds, int seeds, int generated,
                   const std::string& profiles, uint64_t first_seed, int jobs, const std::string& out_dir,
                   const std::string& noise_nominal = "");

}  // namespace irslam::report

#endif  // IRSLAM_TESTS_TOOLS_CLEAN_REPORT_H_
