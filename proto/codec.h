// CAN message definitions and their pure encode/decode functions.
//
// proto/irslam.dbc is the single definition of the bus; the tables in codec.cc
// mirror it signal by signal, and tests/unit/proto_dbc_test.cc parses the DBC and
// checks every signal against these tables so the two cannot drift apart.
#ifndef IRSLAM_PROTO_CODEC_H_
#define IRSLAM_PROTO_CODEC_H_

#include <linux/can.h>

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <variant>

#include "types/signals.h"

namespace irslam::proto {

inline constexpr uint32_t kWheelCmdId = 0x080;
inline constexpr uint32_t kDaemonHeartbeatId = 0x0A0;
inline constexpr uint32_t kControllerStatusId = 0x100;
inline constexpr uint32_t kEncoderId = 0x110;
inline constexpr uint32_t kIrAId = 0x120;
inline constexpr uint32_t kIrBId = 0x121;

// Fault bits of CTRL_STATUS.Faults.
inline constexpr uint8_t kFaultCommandTimeout = 1 << 0;
inline constexpr uint8_t kFaultOvercurrent = 1 << 1;
inline constexpr uint8_t kFaultEncoder = 1 << 2;
inline constexpr uint8_t kFaultIr = 1 << 3;
inline constexpr uint8_t kFaultLowBattery = 1 << 4;
inline constexpr uint8_t kFaultEmergencyStop = 1 << 5;
// Bumper bits of CTRL_STATUS.Bumpers: kBumperLeft, kBumperRight (types/robot.h).

enum class ControllerState : uint8_t { kBoot = 0, kReady = 1, kDriving = 2, kFault = 3 };

struct SignalSpec {
  std::string_view name;
  int start_bit;  // DBC start bit (Intel byte order: LSB position)
  int length;
  bool little_endian;
  bool is_signed;
  double scale;
  double offset;
};

struct MessageSpec {
  std::string_view name;
  uint32_t id;
  uint8_t dlc;
  std::span<const SignalSpec> signals;
};

// Every message irslam puts on or reads from the bus.
std::span<const MessageSpec> AllMessages();
const MessageSpec* FindMessage(uint32_t id);

// Raw (integer) access to a signal in a frame payload; generic over the DBC tables.
uint64_t GetRaw(const uint8_t* data, const SignalSpec& s);
void SetRaw(uint8_t* data, const SignalSpec& s, uint64_t raw);
// Physical value (raw * scale + offset, sign-extended for signed signals).
double GetPhysical(const uint8_t* data, const SignalSpec& s);

// WHEEL_CMD: the command (types/signals.h) and its sequence counter.
struct WheelCmd : WheelCommand {
  uint8_t seq = 0;
};
struct DaemonHeartbeat {
  uint8_t state = 0;
  uint8_t seq = 0;
};
struct ControllerStatus {
  ControllerState state = ControllerState::kBoot;
  uint8_t faults = 0;
  uint8_t bumpers = 0;
  double battery_v = 0;
  uint16_t timestamp_ms = 0;
  uint8_t seq = 0;
};
struct EncoderCounts {
  uint16_t timestamp_ms = 0;
  uint16_t left = 0;
  uint16_t right = 0;
  uint8_t seq = 0;
};
struct IrA {
  uint8_t seq = 0;
  uint16_t timestamp_ms = 0;
  std::array<uint16_t, 3> adc{};  // sensors 0..2
};
struct IrB {
  uint8_t seq = 0;
  std::array<uint16_t, 4> adc{};  // sensors 3..6
};

using Message =
    std::variant<WheelCmd, DaemonHeartbeat, ControllerStatus, EncoderCounts, IrA, IrB>;

enum class DecodeError {
  kNone = 0,
  kNotOurs,    // extended/RTR/error frame or an id we do not know
  kWrongDlc,   // known id, wrong payload length
};
std::string_view ToString(DecodeError e);

struct DecodeResult {
  DecodeError error = DecodeError::kNone;
  Message message;
  bool ok() const { return error == DecodeError::kNone; }
};

can_frame Encode(const Message& m);
DecodeResult Decode(const can_frame& f);

// can-utils compact notation: "123#DEADBEEF".
std::string ToCandumpString(const can_frame& f);
// Parses "123#DEADBEEF" (standard ids only); false on malformed text.
bool ParseCandumpString(std::string_view text, can_frame* f);

}  // namespace irslam::proto

#endif  // IRSLAM_PROTO_CODEC_H_
