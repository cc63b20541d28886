// A minimal DBC reader for tests: messages and signals (Intel byte order) of
// proto/irslam.dbc, and a decoder that knows nothing but the DBC.
#ifndef IRSLAM_TESTS_TESTING_DBC_H_
#define IRSLAM_TESTS_TESTING_DBC_H_

#include <linux/can.h>

#include <cstdint>
#include <map>
#include <string>

namespace irslam::testing {

struct DbcSignal {
  int start, length;
  bool little_endian, is_signed;
  double scale, offset, min, max;
};
struct DbcMessage {
  uint32_t id;
  int dlc;
  std::map<std::string, DbcSignal> signals;
};

std::map<std::string, DbcMessage> ParseDbc(const std::string& path);
double DbcDecode(const can_frame& f, const DbcSignal& s);

}  // namespace irslam::testing

#endif  // IRSLAM_TESTS_TESTING_DBC_H_
