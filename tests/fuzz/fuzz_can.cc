// libFuzzer target: arbitrary CAN frames (16-byte struct can_frame each, ids and
// DLCs included) through the decoder, the motor-controller client and the whole
// core (SLAM, mission), with control periods in between, as irslamd sees them.
#include <linux/can.h>

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "daemon/core_json.h"
#include "robot/robot_core.h"
#include "proto/codec.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  irslam::robot::RobotCore core(irslam::robot::DefaultCoreOptions());
  double t = 0;
  bool started = false;
  for (size_t off = 0; off + sizeof(can_frame) <= size; off += sizeof(can_frame)) {
    can_frame f;
    std::memcpy(&f, data + off, sizeof f);
    (void)irslam::proto::Decode(f);
    (void)irslam::proto::ToCandumpString(f);
    t += 0.002;
    core.OnFrame(f, t);
    if ((off / sizeof(can_frame)) % 10 == 9) {
      std::string why;
      if (!started) started = core.Start(t, &why);
      (void)core.Tick(t);
    }
  }
  (void)irslam::ToJson(core.Status(t)).dump();
  (void)irslam::ToJson(core.Map()).dump();
  return 0;
}
