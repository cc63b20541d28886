#include "tests/testing/dbc.h"

#include <fstream>
#include <regex>

namespace irslam::testing {

std::map<std::string, DbcMessage> ParseDbc(const std::string& path) {
  std::ifstream in(path);
  std::map<std::string, DbcMessage> out;
  const std::regex bo(R"(^BO_ (\d+) (\w+): (\d+) \w+)");
  const std::regex sg(
      R"(^ SG_ (\w+) : (\d+)\|(\d+)@([01])([+-]) \(([-\d.eE]+),([-\d.eE]+)\) \[([-\d.eE]+)\|([-\d.eE]+)\] \"[^\"]*\" .*)");
  std::string line, current;
  std::smatch m;
  while (std::getline(in, line)) {
    if (std::regex_match(line, m, bo)) {
      current = m[2];
      out[current] = {static_cast<uint32_t>(std::stoul(m[1])), std::stoi(m[3]), {}};
    } else if (std::regex_match(line, m, sg)) {
      out[current].signals[m[1]] = {std::stoi(m[2]), std::stoi(m[3]), m[4] == "1", m[5] == "-",
                                    std::stod(m[6]), std::stod(m[7]), std::stod(m[8]),
                                    std::stod(m[9])};
    }
  }
  return out;
}

// A decoder that knows nothing but the DBC (Intel byte order).
double DbcDecode(const can_frame& f, const DbcSignal& s) {
  uint64_t raw = 0;
  for (int i = 0; i < s.length; ++i) {
    const int bit = s.start + i;
    if ((f.data[bit / 8] >> (bit % 8)) & 1) raw |= uint64_t{1} << i;
  }
  double v = static_cast<double>(raw);
  if (s.is_signed && ((raw >> (s.length - 1)) & 1)) {
    v = static_cast<double>(static_cast<int64_t>(raw) - (int64_t{1} << s.length));
  }
  return v * s.scale + s.offset;
}


}  // namespace irslam::testing
