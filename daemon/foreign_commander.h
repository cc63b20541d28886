// A second controller client on the bus (another irslamd, or anything sending
// wheel commands or daemon heartbeats): neither backend delivers a node's own
// frames back to it (SocketCAN without CAN_RAW_RECV_OWN_MSGS; the loopback bus
// sends to the other nodes only), so every WHEEL_CMD or DAEMON_HEARTBEAT frame
// the daemon receives was sent by someone else. Two commanders would fight over
// the wheels: the daemon faults instead (and so does the other irslamd, which
// hears ours). Pure: times are arguments.
#ifndef IRSLAM_DAEMON_FOREIGN_COMMANDER_H_
#define IRSLAM_DAEMON_FOREIGN_COMMANDER_H_

#include <linux/can.h>

#include <cstdint>
#include <nlohmann/json.hpp>

#include "proto/codec.h"

namespace irslam {

// The fault reason (status.reason) while another commander is on the bus.
inline constexpr const char* kForeignCommanderReason = "another controller client on the bus";

class ForeignCommanderWatch {
 public:
  // A commander counts as present for this long after its last frame.
  static constexpr double kPresentS = 2.0;

  static bool IsCommanderFrame(const can_frame& f) {
    if (f.can_id & (CAN_EFF_FLAG | CAN_ERR_FLAG | CAN_RTR_FLAG)) return false;
    const uint32_t id = f.can_id & CAN_SFF_MASK;
    return id == proto::kWheelCmdId || id == proto::kDaemonHeartbeatId;
  }
  // A commander frame received at wall time now_s. True on the first one after a
  // quiet spell (the moment to fault and log).
  bool OnFrame(double now_s) {
    const bool fresh = !Present(now_s);
    ++frames_;
    last_s_ = now_s;
    return fresh;
  }
  bool Present(double now_s) const { return frames_ > 0 && now_s - last_s_ < kPresentS; }
  uint64_t frames() const { return frames_; }

  // status.can members: foreign_commander (present now), foreign_commander_frames,
  // foreign_commander_last (wall seconds since start of the last one; null: never).
  void AddStatus(double now_s, nlohmann::json* can) const {
    (*can)["foreign_commander"] = Present(now_s);
    (*can)["foreign_commander_frames"] = frames_;
    (*can)["foreign_commander_last"] = frames_ ? nlohmann::json(last_s_) : nlohmann::json();
  }

 private:
  uint64_t frames_ = 0;
  double last_s_ = 0;
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_FOREIGN_COMMANDER_H_
