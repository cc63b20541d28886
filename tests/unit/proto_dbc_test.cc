// Checks the codec against proto/irslam.dbc, signal by signal, so the two cannot
// drift apart; and decodes codec-encoded frames with a DBC-driven decoder.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "proto/codec.h"
#include "tests/testing/dbc.h"

namespace irslam::proto {
namespace {

using testing::DbcDecode;
using testing::DbcMessage;
using testing::DbcSignal;
using testing::ParseDbc;

class ProtoDbcTest : public ::testing::Test {
 protected:
  void SetUp() override { dbc_ = ParseDbc(IRSLAM_SOURCE_DIR "/proto/irslam.dbc"); }
  std::map<std::string, DbcMessage> dbc_;
};

TEST_F(ProtoDbcTest, EveryMessageAndSignalMatchesTheDbc) {
  ASSERT_EQ(dbc_.size(), AllMessages().size());
  for (const MessageSpec& m : AllMessages()) {
    SCOPED_TRACE(std::string(m.name));
    ASSERT_TRUE(dbc_.count(std::string(m.name)));
    const DbcMessage& d = dbc_.at(std::string(m.name));
    EXPECT_EQ(d.id, m.id);
    EXPECT_LE(d.id, 0x7FFu) << "standard 11-bit ids only";
    EXPECT_EQ(d.dlc, m.dlc);
    ASSERT_EQ(d.signals.size(), m.signals.size());
    for (const SignalSpec& s : m.signals) {
      SCOPED_TRACE(std::string(s.name));
      ASSERT_TRUE(d.signals.count(std::string(s.name)));
      const DbcSignal& ds = d.signals.at(std::string(s.name));
      EXPECT_EQ(ds.start, s.start_bit);
      EXPECT_EQ(ds.length, s.length);
      EXPECT_EQ(ds.little_endian, s.little_endian);
      EXPECT_EQ(ds.is_signed, s.is_signed);
      EXPECT_DOUBLE_EQ(ds.scale, s.scale);
      EXPECT_DOUBLE_EQ(ds.offset, s.offset);
      EXPECT_LE(s.start_bit + s.length, m.dlc * 8) << "signal runs past the DLC";
    }
  }
}

TEST_F(ProtoDbcTest, SignalsDoNotOverlap) {
  for (const MessageSpec& m : AllMessages()) {
    uint64_t used = 0;
    for (const SignalSpec& s : m.signals) {
      for (int i = 0; i < s.length; ++i) {
        const uint64_t bit = uint64_t{1} << (s.start_bit + i);
        EXPECT_FALSE(used & bit) << m.name << "." << s.name;
        used |= bit;
      }
    }
  }
}

TEST_F(ProtoDbcTest, EncodedFramesDecodeWithTheDbc) {
  const can_frame enc = Encode(EncoderCounts{65535, 1234, 60000, 200});
  const auto& e = dbc_.at("ENCODER").signals;
  EXPECT_DOUBLE_EQ(DbcDecode(enc, e.at("Timestamp")), 65.535);
  EXPECT_DOUBLE_EQ(DbcDecode(enc, e.at("LeftCount")), 1234);
  EXPECT_DOUBLE_EQ(DbcDecode(enc, e.at("RightCount")), 60000);
  EXPECT_DOUBLE_EQ(DbcDecode(enc, e.at("Seq")), 200);

  const can_frame cmd = Encode(WheelCmd{-0.25, 0.5, true, 7});
  const auto& c = dbc_.at("WHEEL_CMD").signals;
  EXPECT_NEAR(DbcDecode(cmd, c.at("LeftVelocity")), -0.25, 1e-12);
  EXPECT_NEAR(DbcDecode(cmd, c.at("RightVelocity")), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(DbcDecode(cmd, c.at("Enable")), 1);
  EXPECT_DOUBLE_EQ(DbcDecode(cmd, c.at("Seq")), 7);

  const can_frame a = Encode(IrA{9, 4321, {0, 4095, 2048}});
  const can_frame b = Encode(IrB{9, {1, 2, 3, 4000}});
  const auto& sa = dbc_.at("IR_A").signals;
  const auto& sb = dbc_.at("IR_B").signals;
  EXPECT_DOUBLE_EQ(DbcDecode(a, sa.at("Timestamp")), 4.321);
  EXPECT_DOUBLE_EQ(DbcDecode(a, sa.at("Ir1")), 4095);
  EXPECT_DOUBLE_EQ(DbcDecode(a, sa.at("Ir2")), 2048);
  EXPECT_DOUBLE_EQ(DbcDecode(b, sb.at("Ir6")), 4000);
  EXPECT_DOUBLE_EQ(DbcDecode(b, sb.at("Seq")), 9);

  const can_frame st = Encode(ControllerStatus{ControllerState::kDriving, kFaultLowBattery,
                                               kBumperRight, 14.4, 100, 3});
  const auto& ss = dbc_.at("CTRL_STATUS").signals;
  EXPECT_DOUBLE_EQ(DbcDecode(st, ss.at("State")), 2);
  EXPECT_DOUBLE_EQ(DbcDecode(st, ss.at("Faults")), kFaultLowBattery);
  EXPECT_DOUBLE_EQ(DbcDecode(st, ss.at("Bumpers")), kBumperRight);
  EXPECT_NEAR(DbcDecode(st, ss.at("Battery")), 14.4, 1e-9);
}

TEST(CodecTest, RoundTripsEveryMessage) {
  const Message msgs[] = {
      WheelCmd{0.123, -0.456, true, 255}, DaemonHeartbeat{5, 17},
      ControllerStatus{ControllerState::kFault, 0x21, 3, 12.001, 65000, 4},
      EncoderCounts{1, 2, 3, 4}, IrA{1, 2, {3, 4, 4095}}, IrB{1, {5, 6, 7, 8}}};
  for (const Message& m : msgs) {
    const DecodeResult r = Decode(Encode(m));
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.message.index(), m.index());
    EXPECT_EQ(Encode(r.message).can_id, Encode(m).can_id);
    EXPECT_EQ(0, std::memcmp(Encode(r.message).data, Encode(m).data, 8));
  }
  const auto cmd = std::get<WheelCmd>(Decode(Encode(WheelCmd{0.123, -0.456, true, 9})).message);
  EXPECT_DOUBLE_EQ(cmd.left_mps, 0.123);
  EXPECT_DOUBLE_EQ(cmd.right_mps, -0.456);
}

TEST(CodecTest, SaturatesOutOfRangeVelocities) {
  const auto cmd = std::get<WheelCmd>(Decode(Encode(WheelCmd{100.0, -100.0, true, 0})).message);
  EXPECT_DOUBLE_EQ(cmd.left_mps, 32.767);
  EXPECT_DOUBLE_EQ(cmd.right_mps, -32.768);
}

TEST(CodecTest, RejectsUnknownIdsWrongDlcAndForeignFrameKinds) {
  can_frame f = Encode(EncoderCounts{1, 2, 3, 4});
  f.can_dlc = 8;
  EXPECT_EQ(Decode(f).error, DecodeError::kWrongDlc);
  f = Encode(EncoderCounts{1, 2, 3, 4});
  f.can_id = 0x7FF;
  EXPECT_EQ(Decode(f).error, DecodeError::kNotOurs);
  f.can_id = kEncoderId | CAN_EFF_FLAG;
  EXPECT_EQ(Decode(f).error, DecodeError::kNotOurs);
  f.can_id = kEncoderId | CAN_RTR_FLAG;
  EXPECT_EQ(Decode(f).error, DecodeError::kNotOurs);
  // Bits above a standard id without the EFF flag (found by fuzzing: it was UB).
  f.can_id = kEncoderId | 0x800;
  EXPECT_EQ(Decode(f).error, DecodeError::kNotOurs);
}

TEST(CodecTest, SpeaksCandumpNotation) {
  const can_frame f = Encode(EncoderCounts{0x1234, 0xABCD, 0x0001, 0x7F});
  EXPECT_EQ(ToCandumpString(f), "110#3412CDAB01007F");
  can_frame g;
  ASSERT_TRUE(ParseCandumpString("110#3412CDAB01007F", &g));
  EXPECT_EQ(g.can_id, kEncoderId);
  EXPECT_EQ(g.can_dlc, 7);
  EXPECT_EQ(0, std::memcmp(f.data, g.data, 7));
  EXPECT_FALSE(ParseCandumpString("110#123", &g));
  EXPECT_FALSE(ParseCandumpString("1G0#12", &g));
  EXPECT_FALSE(ParseCandumpString("110#001122334455667788", &g));
  EXPECT_FALSE(ParseCandumpString("800#00", &g));
}

}  // namespace
}  // namespace irslam::proto
