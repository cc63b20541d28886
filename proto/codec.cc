#include "proto/codec.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace irslam::proto {
namespace {

// These tables mirror proto/irslam.dbc (checked by tests/unit/proto_dbc_test.cc).
constexpr SignalSpec kWheelCmdSignals[] = {
    {"LeftVelocity", 0, 16, true, true, 0.001, 0},
    {"RightVelocity", 16, 16, true, true, 0.001, 0},
    {"Enable", 32, 1, true, false, 1, 0},
    {"Seq", 40, 8, true, false, 1, 0},
};
constexpr SignalSpec kDaemonHeartbeatSignals[] = {
    {"State", 0, 8, true, false, 1, 0},
    {"Seq", 8, 8, true, false, 1, 0},
};
constexpr SignalSpec kControllerStatusSignals[] = {
    {"State", 0, 8, true, false, 1, 0},      {"Faults", 8, 8, true, false, 1, 0},
    {"Bumpers", 16, 8, true, false, 1, 0},   {"Battery", 24, 16, true, false, 0.001, 0},
    {"Timestamp", 40, 16, true, false, 0.001, 0}, {"Seq", 56, 8, true, false, 1, 0},
};
constexpr SignalSpec kEncoderSignals[] = {
    {"Timestamp", 0, 16, true, false, 0.001, 0},
    {"LeftCount", 16, 16, true, false, 1, 0},
    {"RightCount", 32, 16, true, false, 1, 0},
    {"Seq", 48, 8, true, false, 1, 0},
};
constexpr SignalSpec kIrASignals[] = {
    {"Seq", 0, 8, true, false, 1, 0},   {"Timestamp", 8, 16, true, false, 0.001, 0},
    {"Ir0", 24, 12, true, false, 1, 0}, {"Ir1", 36, 12, true, false, 1, 0},
    {"Ir2", 48, 12, true, false, 1, 0},
};
constexpr SignalSpec kIrBSignals[] = {
    {"Seq", 0, 8, true, false, 1, 0},   {"Ir3", 8, 12, true, false, 1, 0},
    {"Ir4", 20, 12, true, false, 1, 0}, {"Ir5", 32, 12, true, false, 1, 0},
    {"Ir6", 44, 12, true, false, 1, 0},
};

constexpr MessageSpec kMessages[] = {
    {"WHEEL_CMD", kWheelCmdId, 6, kWheelCmdSignals},
    {"DAEMON_HEARTBEAT", kDaemonHeartbeatId, 2, kDaemonHeartbeatSignals},
    {"CTRL_STATUS", kControllerStatusId, 8, kControllerStatusSignals},
    {"ENCODER", kEncoderId, 7, kEncoderSignals},
    {"IR_A", kIrAId, 8, kIrASignals},
    {"IR_B", kIrBId, 7, kIrBSignals},
};

// Physical -> raw with rounding and saturation to the signal's range.
uint64_t ToRaw(const SignalSpec& s, double physical) {
  double raw = std::round((physical - s.offset) / s.scale);
  if (s.is_signed) {
    const double lo = -std::ldexp(1.0, s.length - 1);
    const double hi = std::ldexp(1.0, s.length - 1) - 1;
    raw = std::clamp(raw, lo, hi);
    const auto v = static_cast<int64_t>(raw);
    const uint64_t mask = s.length == 64 ? ~uint64_t{0} : ((uint64_t{1} << s.length) - 1);
    return static_cast<uint64_t>(v) & mask;
  }
  const double hi = std::ldexp(1.0, s.length) - 1;
  raw = std::clamp(raw, 0.0, hi);
  return static_cast<uint64_t>(raw);
}

class Writer {
 public:
  Writer(const MessageSpec& spec) : spec_(spec) {
    std::memset(&frame_, 0, sizeof(frame_));
    frame_.can_id = spec.id;
    frame_.can_dlc = spec.dlc;
  }
  Writer& Raw(size_t i, uint64_t raw) {
    SetRaw(frame_.data, spec_.signals[i], raw);
    return *this;
  }
  Writer& Phys(size_t i, double v) { return Raw(i, ToRaw(spec_.signals[i], v)); }
  can_frame frame() const { return frame_; }

 private:
  const MessageSpec& spec_;
  can_frame frame_;
};

const MessageSpec& Spec(uint32_t id) { return *FindMessage(id); }

uint64_t Raw(const can_frame& f, size_t i) { return GetRaw(f.data, Spec(f.can_id).signals[i]); }

}  // namespace

std::span<const MessageSpec> AllMessages() { return kMessages; }

const MessageSpec* FindMessage(uint32_t id) {
  for (const auto& m : kMessages) {
    if (m.id == id) return &m;
  }
  return nullptr;
}

uint64_t GetRaw(const uint8_t* data, const SignalSpec& s) {
  uint64_t v = 0;
  for (int i = 0; i < s.length; ++i) {
    const int bit = s.start_bit + i;
    if ((data[bit / 8] >> (bit % 8)) & 1) v |= uint64_t{1} << i;
  }
  return v;
}

void SetRaw(uint8_t* data, const SignalSpec& s, uint64_t raw) {
  for (int i = 0; i < s.length; ++i) {
    const int bit = s.start_bit + i;
    const auto mask = static_cast<uint8_t>(1u << (bit % 8));
    if ((raw >> i) & 1) {
      data[bit / 8] = static_cast<uint8_t>(data[bit / 8] | mask);
    } else {
      data[bit / 8] = static_cast<uint8_t>(data[bit / 8] & ~mask);
    }
  }
}

double GetPhysical(const uint8_t* data, const SignalSpec& s) {
  const uint64_t raw = GetRaw(data, s);
  double v;
  if (s.is_signed && s.length < 64 && ((raw >> (s.length - 1)) & 1)) {
    v = static_cast<double>(static_cast<int64_t>(raw) - (int64_t{1} << s.length));
  } else {
    v = static_cast<double>(raw);
  }
  return v * s.scale + s.offset;
}

std::string_view ToString(DecodeError e) {
  switch (e) {
    case DecodeError::kNone: return "ok";
    case DecodeError::kNotOurs: return "unknown_id";
    case DecodeError::kWrongDlc: return "wrong_dlc";
  }
  return "?";
}

can_frame Encode(const Message& m) {
  struct Visitor {
    can_frame operator()(const WheelCmd& c) const {
      return Writer(Spec(kWheelCmdId))
          .Phys(0, c.left_mps).Phys(1, c.right_mps).Raw(2, c.enable ? 1 : 0).Raw(3, c.seq)
          .frame();
    }
    can_frame operator()(const DaemonHeartbeat& h) const {
      return Writer(Spec(kDaemonHeartbeatId)).Raw(0, h.state).Raw(1, h.seq).frame();
    }
    can_frame operator()(const ControllerStatus& s) const {
      return Writer(Spec(kControllerStatusId))
          .Raw(0, static_cast<uint8_t>(s.state)).Raw(1, s.faults).Raw(2, s.bumpers)
          .Phys(3, s.battery_v).Raw(4, s.timestamp_ms).Raw(5, s.seq)
          .frame();
    }
    can_frame operator()(const EncoderCounts& e) const {
      return Writer(Spec(kEncoderId))
          .Raw(0, e.timestamp_ms).Raw(1, e.left).Raw(2, e.right).Raw(3, e.seq)
          .frame();
    }
    can_frame operator()(const IrA& a) const {
      Writer w(Spec(kIrAId));
      w.Raw(0, a.seq).Raw(1, a.timestamp_ms);
      for (size_t i = 0; i < a.adc.size(); ++i) w.Raw(2 + i, std::min<uint16_t>(a.adc[i], 4095));
      return w.frame();
    }
    can_frame operator()(const IrB& b) const {
      Writer w(Spec(kIrBId));
      w.Raw(0, b.seq);
      for (size_t i = 0; i < b.adc.size(); ++i) w.Raw(1 + i, std::min<uint16_t>(b.adc[i], 4095));
      return w.frame();
    }
  };
  return std::visit(Visitor{}, m);
}

DecodeResult Decode(const can_frame& f) {
  DecodeResult r;
  if (f.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG)) {
    r.error = DecodeError::kNotOurs;
    return r;
  }
  // A standard frame's id has 11 bits; anything above them (possible on the
  // loopback bus, which carries whatever a local process sends) is not a frame of
  // ours (found by fuzzing).
  if ((f.can_id & CAN_EFF_MASK) > CAN_SFF_MASK) {
    r.error = DecodeError::kNotOurs;
    return r;
  }
  const MessageSpec* spec = FindMessage(f.can_id & CAN_SFF_MASK);
  if (spec == nullptr) {
    r.error = DecodeError::kNotOurs;
    return r;
  }
  if (f.can_dlc != spec->dlc) {
    r.error = DecodeError::kWrongDlc;
    return r;
  }
  const auto u8 = [&](size_t i) { return static_cast<uint8_t>(Raw(f, i)); };
  const auto u16 = [&](size_t i) { return static_cast<uint16_t>(Raw(f, i)); };
  switch (spec->id) {
    case kWheelCmdId:
      r.message = WheelCmd{GetPhysical(f.data, spec->signals[0]),
                               GetPhysical(f.data, spec->signals[1]), Raw(f, 2) != 0, u8(3)};
      break;
    case kDaemonHeartbeatId:
      r.message = DaemonHeartbeat{u8(0), u8(1)};
      break;
    case kControllerStatusId:
      r.message = ControllerStatus{static_cast<ControllerState>(u8(0)), u8(1), u8(2),
                                   GetPhysical(f.data, spec->signals[3]), u16(4), u8(5)};
      break;
    case kEncoderId:
      r.message = EncoderCounts{u16(0), u16(1), u16(2), u8(3)};
      break;
    case kIrAId:
      r.message = IrA{u8(0), u16(1), {u16(2), u16(3), u16(4)}};
      break;
    case kIrBId:
      r.message = IrB{u8(0), {u16(1), u16(2), u16(3), u16(4)}};
      break;
  }
  return r;
}

std::string ToCandumpString(const can_frame& f) {
  char buf[64];
  int n;
  if (f.can_id & CAN_EFF_FLAG) {
    n = std::snprintf(buf, sizeof buf, "%08X#", f.can_id & CAN_EFF_MASK);
  } else {
    n = std::snprintf(buf, sizeof buf, "%03X#", f.can_id & CAN_SFF_MASK);
  }
  std::string s(buf, static_cast<size_t>(n));
  for (int i = 0; i < f.can_dlc && i < 8; ++i) {
    std::snprintf(buf, sizeof buf, "%02X", f.data[i]);
    s += buf;
  }
  return s;
}

bool ParseCandumpString(std::string_view text, can_frame* f) {
  const auto hash = text.find('#');
  if (hash == std::string_view::npos || hash != 3) return false;
  const auto hex = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  std::memset(f, 0, sizeof(*f));
  uint32_t id = 0;
  for (size_t i = 0; i < 3; ++i) {
    const int h = hex(text[i]);
    if (h < 0) return false;
    id = id * 16 + static_cast<uint32_t>(h);
  }
  if (id > CAN_SFF_MASK) return false;
  const std::string_view data = text.substr(4);
  if (data.size() % 2 != 0 || data.size() > 16) return false;
  for (size_t i = 0; i < data.size() / 2; ++i) {
    const int hi = hex(data[2 * i]);
    const int lo = hex(data[2 * i + 1]);
    if (hi < 0 || lo < 0) return false;
    f->data[i] = static_cast<uint8_t>(hi * 16 + lo);
  }
  f->can_id = id;
  f->can_dlc = static_cast<uint8_t>(data.size() / 2);
  return true;
}

}  // namespace irslam::proto
