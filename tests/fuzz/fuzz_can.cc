// libFuzzer target: arbitrary CAN frames (16-byte struct can_frame each, ids and
// DLCs included) through the decoder (proto::Decode, the candump text), the
// motor-controller client and the whole core (SLAM, mission) as irslamd sees
// them: 2 ms apart, a control period (Tick) after every 10th frame, `start` at
// the first period it is allowed; then the core's status and map serialised as
// the API serves them. A fresh core per input, so no state carries over.
// Slower than the parsers (about 1.6 ms per input with ASan on this 2-core
// host): the time is the core's own work (the EKF's predict per wheel-tick
// frame, the decoder, the JSON), not the harness; the core is not reused across
// inputs, which would make a crash depend on earlier inputs.
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
