#include <gtest/gtest.h>

#include "drivers/motor_client.h"

namespace irslam::drivers {
namespace {

using proto::Encode;

TEST(Unwrapper16Test, UnwrapsAcrossTheWrapBothWays) {
  Unwrapper16 u;
  EXPECT_EQ(u.Update(65530), 65530);
  EXPECT_EQ(u.Update(4), 65540);
  EXPECT_EQ(u.Update(65534), 65534);  // backwards across the wrap
  EXPECT_EQ(u.Update(100), 65636);
}

TEST(MotorClientTest, EncoderCountsAreUnwrappedAndTimestamped) {
  MotorClient c{MotorClientOptions{}};
  auto ev = c.Handle(Encode(proto::EncoderCounts{65530, 65500, 10, 0}), 0.0);
  ASSERT_TRUE(ev.ticks);
  EXPECT_DOUBLE_EQ(ev.ticks->t, 65.530);
  ev = c.Handle(Encode(proto::EncoderCounts{4, 30, 65500, 1}), 0.01);  // both wrap
  ASSERT_TRUE(ev.ticks);
  EXPECT_DOUBLE_EQ(ev.ticks->t, 65.540);
  EXPECT_EQ(ev.ticks->left - 65500, 66);
  EXPECT_EQ(ev.ticks->right - 10, -46);
  EXPECT_EQ(c.counters().seq_gap_encoder, 0u);
}

TEST(MotorClientTest, CountsSequenceGaps) {
  MotorClient c{MotorClientOptions{}};
  c.Handle(Encode(proto::EncoderCounts{0, 0, 0, 254}), 0);
  c.Handle(Encode(proto::EncoderCounts{10, 0, 0, 255}), 0);
  c.Handle(Encode(proto::EncoderCounts{20, 0, 0, 0}), 0);  // wraps: no gap
  c.Handle(Encode(proto::EncoderCounts{40, 0, 0, 2}), 0);  // 1 missing
  EXPECT_EQ(c.counters().seq_gap_encoder, 1u);
}

TEST(MotorClientTest, PairsIrHalvesBySequence) {
  MotorClient c{MotorClientOptions{}};
  EXPECT_FALSE(c.Handle(Encode(proto::IrA{5, 1000, {1, 2, 3}}), 0).ir_adc);
  auto ev = c.Handle(Encode(proto::IrB{5, {4, 5, 6, 7}}), 0);
  ASSERT_TRUE(ev.ir_adc);
  EXPECT_EQ(*ev.ir_adc, (std::array<uint16_t, 7>{1, 2, 3, 4, 5, 6, 7}));
  EXPECT_DOUBLE_EQ(ev.ir_t, 1.0);
  // A B half without its A half is dropped and counted.
  c.Handle(Encode(proto::IrA{6, 1038, {1, 2, 3}}), 0);
  EXPECT_FALSE(c.Handle(Encode(proto::IrB{7, {4, 5, 6, 7}}), 0).ir_adc);
  EXPECT_EQ(c.counters().ir_unpaired, 2u);
  EXPECT_EQ(c.counters().ir_samples, 1u);
}

TEST(MotorClientTest, DetectsControllerLossAndRecovery) {
  MotorClient c{MotorClientOptions{0.1}};
  EXPECT_FALSE(c.ControllerAlive(0));
  c.Handle(Encode(proto::EncoderCounts{0, 0, 0, 0}), 1.00);
  c.Handle(Encode(proto::ControllerStatus{}), 1.00);
  EXPECT_TRUE(c.ControllerAlive(1.05));
  EXPECT_FALSE(c.ControllerAlive(1.11));
  EXPECT_STREQ(c.LossReason(1.11), "encoder frames timed out");
  c.Handle(Encode(proto::EncoderCounts{120, 0, 0, 1}), 1.12);
  EXPECT_TRUE(c.ControllerAlive(1.13));
}

TEST(MotorClientTest, ControllerResetKeepsTimeAndCountsContinuous) {
  MotorClient c{MotorClientOptions{}};
  c.Handle(Encode(proto::EncoderCounts{30000, 5000, 6000, 10}), 10.00);
  auto before = c.Handle(Encode(proto::EncoderCounts{30010, 5010, 6010, 11}), 10.01);
  // The controller restarts: its clock and counters start again from zero. Two
  // frames are held back as possibly corrupt; the third that agrees re-anchors.
  EXPECT_FALSE(c.Handle(Encode(proto::EncoderCounts{5, 0, 0, 0}), 10.50).ticks);
  EXPECT_FALSE(c.Handle(Encode(proto::EncoderCounts{15, 3, 4, 1}), 10.51).ticks);
  auto after = c.Handle(Encode(proto::EncoderCounts{25, 6, 8, 2}), 10.52);
  ASSERT_TRUE(before.ticks && after.ticks);
  EXPECT_EQ(c.counters().controller_resets, 1u);
  EXPECT_EQ(c.counters().implausible_time, 3u);
  // Time carries on with the host's elapsed time; the counts without a jump.
  EXPECT_NEAR(after.ticks->t - before.ticks->t, 0.51, 1e-9);
  EXPECT_EQ(after.ticks->left, before.ticks->left);
  EXPECT_EQ(after.ticks->right, before.ticks->right);
  auto next = c.Handle(Encode(proto::EncoderCounts{35, 13, 17, 3}), 10.53);
  ASSERT_TRUE(next.ticks);
  EXPECT_EQ(next.ticks->left - after.ticks->left, 7);
  EXPECT_EQ(next.ticks->right - after.ticks->right, 9);
  EXPECT_EQ(c.counters().seq_gap_encoder, 0u);
}

TEST(MotorClientTest, ACorruptTimeStampIsDroppedAndCounted) {
  MotorClient c{MotorClientOptions{}};
  c.Handle(Encode(proto::EncoderCounts{1000, 100, 100, 0}), 1.00);
  // Bit 14 of the stamp flipped: 16 s ahead of the clock.
  EXPECT_FALSE(c.Handle(Encode(proto::EncoderCounts{1010 | 0x4000, 102, 102, 1}), 1.01).ticks);
  auto ok = c.Handle(Encode(proto::EncoderCounts{1020, 104, 104, 2}), 1.02);
  ASSERT_TRUE(ok.ticks);
  EXPECT_DOUBLE_EQ(ok.ticks->t, 1.020);
  EXPECT_EQ(c.counters().implausible_time, 1u);
  EXPECT_EQ(c.counters().controller_resets + c.counters().clock_jumps, 0u);
}

TEST(MotorClientTest, DuplicatedAndReorderedFramesAreDropped) {
  MotorClient c{MotorClientOptions{}};
  EXPECT_TRUE(c.Handle(Encode(proto::EncoderCounts{1000, 0, 0, 0}), 1.0).ticks);
  EXPECT_TRUE(c.Handle(Encode(proto::EncoderCounts{1020, 4, 4, 2}), 1.02).ticks);
  EXPECT_FALSE(c.Handle(Encode(proto::EncoderCounts{1020, 4, 4, 2}), 1.02).ticks);  // duplicate
  EXPECT_FALSE(c.Handle(Encode(proto::EncoderCounts{1010, 2, 2, 1}), 1.02).ticks);  // late
  EXPECT_EQ(c.counters().duplicate, 1u);
  EXPECT_EQ(c.counters().stale, 1u);
  // IR: a duplicated half is not a second sample.
  c.Handle(Encode(proto::IrA{7, 1030, {1, 2, 3}}), 1.03);
  c.Handle(Encode(proto::IrA{7, 1030, {1, 2, 3}}), 1.03);
  EXPECT_TRUE(c.Handle(Encode(proto::IrB{7, {4, 5, 6, 7}}), 1.03).ir_adc);
  EXPECT_FALSE(c.Handle(Encode(proto::IrB{7, {4, 5, 6, 7}}), 1.03).ir_adc);
  EXPECT_EQ(c.counters().duplicate, 3u);
  EXPECT_EQ(c.counters().ir_samples, 1u);
  EXPECT_EQ(c.counters().ir_unpaired, 0u);
}

TEST(MotorClientTest, ImpossibleCountJumpsNeverReachTheCaller) {
  MotorClientOptions o;
  o.max_counts_per_s = 10000;  // 100 counts per 10 ms frame, + 20 slack
  MotorClient c{o};
  c.Handle(Encode(proto::EncoderCounts{1000, 100, 100, 0}), 1.0);
  // A one-frame glitch: dropped, the next frame continues from the last good one.
  EXPECT_FALSE(c.Handle(Encode(proto::EncoderCounts{1010, 100 + 4096, 150, 1}), 1.01).ticks);
  auto ok = c.Handle(Encode(proto::EncoderCounts{1020, 180, 180, 2}), 1.02);
  ASSERT_TRUE(ok.ticks);
  EXPECT_EQ(ok.ticks->left, 180);
  // A jump that stays: three frames in a row, then carried on from the new count
  // without the jump (the motion of the held frames is lost, not the jump added).
  for (int i = 0; i < 2; ++i) {
    EXPECT_FALSE(c.Handle(Encode(proto::EncoderCounts{static_cast<uint16_t>(1030 + 10 * i),
                                                      static_cast<uint16_t>(5180 + 10 * i), 190, 3}),
                          1.03 + 0.01 * i)
                     .ticks);
  }
  auto third = c.Handle(Encode(proto::EncoderCounts{1050, 5200, 200, 5}), 1.05);
  ASSERT_TRUE(third.ticks);
  EXPECT_EQ(third.ticks->left, 180);
  auto next = c.Handle(Encode(proto::EncoderCounts{1060, 5210, 210, 6}), 1.06);
  EXPECT_EQ(next.ticks->left, 190);
  EXPECT_EQ(c.counters().implausible_counts, 4u);
}

TEST(MotorClientTest, AStampThatDisagreesWithItsSequenceNumberIsDropped) {
  MotorClient c{MotorClientOptions{}};
  // Learn the encoder period (10 ms per sequence step).
  for (int i = 0; i < 12; ++i) {
    ASSERT_TRUE(c.Handle(Encode(proto::EncoderCounts{static_cast<uint16_t>(1000 + 10 * i), 0, 0,
                                                     static_cast<uint8_t>(i)}),
                         1.0 + 0.01 * i)
                    .ticks);
  }
  // Bit 8 of the stamp flipped: 256 ms ahead, near enough to the clock to pass
  // the clock check, but 256 ms is not one sequence step.
  EXPECT_FALSE(c.Handle(Encode(proto::EncoderCounts{1120 + 256, 0, 0, 12}), 1.12).ticks);
  auto ok = c.Handle(Encode(proto::EncoderCounts{1130, 0, 0, 13}), 1.13);
  ASSERT_TRUE(ok.ticks);
  EXPECT_DOUBLE_EQ(ok.ticks->t, 1.130);
  EXPECT_EQ(c.counters().implausible_time, 1u);
  EXPECT_EQ(c.counters().stale, 0u);
}

TEST(MotorClientTest, ALongSilenceWithoutResetIsNotAJump) {
  MotorClient c{MotorClientOptions{}};
  c.Handle(Encode(proto::EncoderCounts{1000, 0, 0, 0}), 1.0);
  auto ev = c.Handle(Encode(proto::EncoderCounts{4000, 0, 0, 1}), 4.0);  // 3 s later on both clocks
  ASSERT_TRUE(ev.ticks);
  EXPECT_DOUBLE_EQ(ev.ticks->t, 4.0);
  EXPECT_EQ(c.counters().implausible_time, 0u);
}

TEST(MotorClientTest, CountsBadFramesByReason) {
  MotorClient c{MotorClientOptions{}};
  can_frame f = Encode(proto::EncoderCounts{});
  f.can_dlc = 3;
  c.Handle(f, 0);
  f.can_id = 0x555;
  c.Handle(f, 0);
  c.Handle(Encode(proto::WheelCmd{}), 0);  // another node's command: not for us
  EXPECT_EQ(c.counters().wrong_dlc, 1u);
  EXPECT_EQ(c.counters().unknown_id, 1u);
  EXPECT_EQ(c.counters().ignored, 1u);
  EXPECT_EQ(c.counters().encoder_frames, 0u);
}

TEST(MotorClientTest, CommandsCarrySequenceAndZeroWhenDisabled) {
  MotorClient c{MotorClientOptions{}};
  auto a = std::get<proto::WheelCmd>(proto::Decode(c.MakeCommand({0.1, 0.2, true})).message);
  auto b = std::get<proto::WheelCmd>(proto::Decode(c.MakeCommand({0.1, 0.2, false})).message);
  EXPECT_EQ(a.seq + 1, b.seq);
  EXPECT_DOUBLE_EQ(a.right_mps, 0.2);
  EXPECT_FALSE(b.enable);
  EXPECT_DOUBLE_EQ(b.left_mps, 0.0);
}

// A bumper bit of CTRL_STATUS counts only when two frames in a row carry it: a
// real contact lasts (the robot is stopped against the obstacle), a flipped bit
// does not. The bits set in one frame only are counted.
TEST(MotorClientTest, ABumperBitIsConfirmedByTwoStatusFramesInARow) {
  MotorClient c{MotorClientOptions{}};
  proto::ControllerStatus st;
  st.state = proto::ControllerState::kReady;
  const auto send = [&](uint8_t bumpers, int i) {
    st.bumpers = bumpers;
    st.seq = static_cast<uint8_t>(i);
    st.timestamp_ms = static_cast<uint16_t>(1000 + 50 * i);
    return c.Handle(Encode(st), 1.0 + 0.05 * i);
  };
  // The confirmed bits the event carries (0xFF: none).
  const auto bits = [&](uint8_t bumpers, int i) { return send(bumpers, i).bumpers.value_or(0xFF); };
  EXPECT_EQ(bits(0, 0), 0);
  EXPECT_EQ(bits(kBumperLeft, 1), 0);  // a flipped bit: one frame only
  EXPECT_EQ(bits(0, 2), 0);
  EXPECT_EQ(c.counters().bumper_unconfirmed, 1u);
  EXPECT_EQ(bits(kBumperRight, 3), 0);  // a real contact: it lasts
  EXPECT_EQ(bits(kBumperRight, 4), kBumperRight);
  EXPECT_EQ(c.bumpers(), kBumperRight);
  EXPECT_EQ(bits(kBumperRight | kBumperLeft, 5), kBumperRight);
  EXPECT_EQ(bits(kBumperRight | kBumperLeft, 6), kBumperRight | kBumperLeft);
  EXPECT_EQ(bits(0, 7), 0);  // released: at once
  EXPECT_EQ(c.bumpers(), 0);
  EXPECT_EQ(c.counters().bumper_unconfirmed, 1u);
  // Frames without status do not carry bumpers; the confirmed bits stay.
  send(kBumperLeft, 8);
  send(kBumperLeft, 9);
  EXPECT_FALSE(c.Handle(Encode(proto::EncoderCounts{1500, 0, 0, 0}), 1.5).bumpers);
  EXPECT_EQ(c.bumpers(), kBumperLeft);
}

TEST(MotorClientTest, ARejectedStatusFrameDoesNotMoveTheBumpers) {
  MotorClient c{MotorClientOptions{}};
  proto::ControllerStatus st;
  st.bumpers = kBumperLeft;
  st.timestamp_ms = 1000;
  EXPECT_TRUE(c.Handle(Encode(st), 1.0).bumpers);
  st.seq = 1;
  st.timestamp_ms = 31000;  // 30 s ahead of the controller's clock: dropped
  EXPECT_FALSE(c.Handle(Encode(st), 1.05).bumpers);
  EXPECT_EQ(c.counters().implausible_time, 1u);
  EXPECT_EQ(c.bumpers(), 0) << "one frame so far";
  st.seq = 2;
  st.timestamp_ms = 1100;
  EXPECT_EQ(c.Handle(Encode(st), 1.1).bumpers.value_or(0xFF), kBumperLeft);
}

}  // namespace
}  // namespace irslam::drivers
