// The simulator's fault injection (sim/faults.h): the SPEC grammar and what
// each fault does to the controller's frames.
#include <gtest/gtest.h>

#include "proto/codec.h"
#include "sim/faults.h"

namespace irslam::sim {
namespace {

TEST(FaultSpecTest, ParsesEveryFault) {
  std::string error;
  auto f = ParseFaultSpec(
      "loss:p=0.1,burst:every=10:len=0.2,corrupt:p=0.01,duplicate:p=0.05,reorder:p=0.02,delay:p=0.1:max=0.03,"
      "silence:at=5:for=1:reset=1,flood:at=2:for=3:rate=1000,stuck_ir:sensor=3:at=4,"
      "encoder_glitch:at=6:counts=500:wheel=both",
      &error);
  ASSERT_TRUE(f) << error;
  EXPECT_DOUBLE_EQ(f->loss_p, 0.1);
  EXPECT_DOUBLE_EQ(f->burst_len_s, 0.2);
  EXPECT_DOUBLE_EQ(f->delay_max_s, 0.03);
  ASSERT_EQ(f->silence.size(), 1u);
  EXPECT_TRUE(f->silence_reset[0]);
  EXPECT_DOUBLE_EQ(f->flood_rate, 1000);
  EXPECT_EQ(f->stuck_ir[0].sensor, 3);
  EXPECT_TRUE(f->encoder_glitch[0].left && f->encoder_glitch[0].right);
  EXPECT_TRUE(f->any());
  EXPECT_FALSE(ParseFaultSpec("", &error)->any());
}

TEST(FaultSpecTest, BadSpecsGiveOneLineNamingThePart) {
  const std::pair<const char*, const char*> cases[] = {
      {"gremlins:p=1", "faults: unknown fault 'gremlins'"},
      {"loss", "faults: 'loss': needs p="},
      {"loss:p=2", "faults: 'loss:p=2': p must be in [0, 1] (got 2)"},
      {"loss:p=x", "faults: 'loss:p=x': p must be a number"},
      {"loss:q=0.1", "faults: 'loss:q=0.1': needs p="},
      {"loss:p=0.1:q=1", "faults: 'loss:p=0.1:q=1': unknown key 'q'"},
      {"silence:at=1", "faults: 'silence:at=1': needs for="},
      {"encoder_glitch:at=1:counts=5:wheel=front", "faults: 'encoder_glitch:at=1:counts=5:wheel=front': wheel must be"},
      {"loss:0.1", "faults: 'loss:0.1': expected KEY=VALUE"},
  };
  for (const auto& [spec, want] : cases) {
    std::string error;
    EXPECT_FALSE(ParseFaultSpec(spec, &error)) << spec;
    EXPECT_EQ(error.rfind(want, 0), 0u) << spec << " -> " << error;
  }
}

TEST(FaultSpecTest, EveryFaultsKeysComeFromItsTable) {
  // Unknown keys, bounds, integers and words: the same checks and words for every fault.
  const std::pair<const char*, const char*> cases[] = {
      {"burst:every=1:len=1:width=3", "faults: 'burst:every=1:len=1:width=3': unknown key 'width'"},
      {"delay:p=0.1:min=0", "faults: 'delay:p=0.1:min=0': unknown key 'min'"},
      {"flood:at=0:for=1:id=5", "faults: 'flood:at=0:for=1:id=5': unknown key 'id'"},
      {"delay:p=0.1:max=11", "faults: 'delay:p=0.1:max=11': max must be in [0, 10] (got 11)"},
      {"silence:at=-1:for=1", "faults: 'silence:at=-1:for=1': at must be in [0, 1000000] (got -1)"},
      {"silence:at=1:for=1:reset=2", "faults: 'silence:at=1:for=1:reset=2': reset must be in [0, 1] (got 2)"},
      {"flood:at=0:for=1:rate=2e6", "faults: 'flood:at=0:for=1:rate=2e6': rate must be in [0, 1000000] (got 2000000)"},
      {"stuck_ir:sensor=7:at=1", "faults: 'stuck_ir:sensor=7:at=1': sensor must be in [0, 6] (got 7)"},
      {"stuck_ir:sensor=2.5:at=1", "faults: 'stuck_ir:sensor=2.5:at=1': sensor must be an integer"},
      {"encoder_glitch:at=1:counts=40000", "faults: 'encoder_glitch:at=1:counts=40000': counts must be in [0, 30000] (got 40000)"},
      {"encoder_glitch:at=1:counts=5:wheel=2", "faults: 'encoder_glitch:at=1:counts=5:wheel=2': wheel must be a string"},
      {"corrupt:p=nan", "faults: 'corrupt:p=nan': p must be a number"},
  };
  for (const auto& [spec, want] : cases) {
    std::string error;
    EXPECT_FALSE(ParseFaultSpec(spec, &error)) << spec;
    EXPECT_EQ(error, want) << spec;
  }
  // Defaults of keys not given, and a flood without rate= keeps an earlier one's.
  std::string error;
  auto f = ParseFaultSpec("delay:p=0.5,stuck_ir:sensor=6:at=1,flood:at=0:for=1:rate=100,flood:at=5:for=1",
                          &error);
  ASSERT_TRUE(f) << error;
  EXPECT_DOUBLE_EQ(f->delay_max_s, 0.02);
  EXPECT_EQ(f->stuck_ir[0].sensor, 6);
  EXPECT_DOUBLE_EQ(f->stuck_ir[0].when.len, 1e9);
  EXPECT_EQ(f->flood.size(), 2u);
  EXPECT_DOUBLE_EQ(f->flood_rate, 100);
}

std::vector<can_frame> Enc(uint16_t stamp, uint16_t l, uint16_t r, uint8_t seq) {
  return {proto::Encode(proto::EncoderCounts{stamp, l, r, seq})};
}

proto::EncoderCounts AsEnc(const can_frame& f) { return std::get<proto::EncoderCounts>(proto::Decode(f).message); }

TEST(FaultInjectorTest, SilenceWithResetRestartsClockCountsAndSequences) {
  std::string error;
  FaultInjector inj(*ParseFaultSpec("silence:at=1:for=0.5:reset=1", &error), 1);
  std::vector<can_frame> out;
  inj.Process(0.99, Enc(990, 1000, 2000, 99), &out);
  inj.Process(1.2, Enc(1200, 1040, 2040, 120), &out);  // silent
  ASSERT_EQ(out.size(), 1u);
  inj.Process(1.6, Enc(1600, 1120, 2120, 160), &out);
  inj.Process(1.61, Enc(1610, 1122, 2122, 161), &out);
  ASSERT_EQ(out.size(), 3u);
  const auto a = AsEnc(out[1]), b = AsEnc(out[2]);
  EXPECT_EQ(a.timestamp_ms, 5);
  EXPECT_EQ(a.left, 0);
  EXPECT_EQ(a.seq, 0);
  EXPECT_EQ(b.timestamp_ms, 15);
  EXPECT_EQ(b.left, 2);
  EXPECT_EQ(b.right, 2);
  EXPECT_EQ(b.seq, 1);
  EXPECT_EQ(inj.counters().silenced, 1u);
}

TEST(FaultInjectorTest, GlitchStuckSensorAndFlood) {
  std::string error;
  FaultInjector inj(*ParseFaultSpec("encoder_glitch:at=1:counts=5000,stuck_ir:sensor=4:at=1:for=1,flood:at=0:for=1:rate=1000",
                                    &error),
                    1);
  std::vector<can_frame> out;
  inj.Process(0.5, Enc(500, 100, 100, 1), &out);
  inj.Process(1.0, Enc(1000, 110, 110, 2), &out);
  EXPECT_EQ(AsEnc(out[0]).left, 100);
  EXPECT_EQ(AsEnc(out[1]).left, 5110);  // the jump stays
  EXPECT_EQ(AsEnc(out[1]).right, 110);
  out.clear();
  inj.Process(1.1, {proto::Encode(proto::IrB{1, {10, 20, 30, 40}})}, &out);
  inj.Process(1.2, {proto::Encode(proto::IrB{2, {11, 21, 31, 41}})}, &out);
  inj.Process(2.2, {proto::Encode(proto::IrB{3, {12, 22, 32, 42}})}, &out);
  const auto ir = [&](size_t i) { return std::get<proto::IrB>(proto::Decode(out[i]).message).adc; };
  EXPECT_EQ(ir(1)[1], 20);  // sensor 4 = IR_B's second value: stuck at 20
  EXPECT_EQ(ir(1)[0], 11);
  EXPECT_EQ(ir(2)[1], 22);  // the window is over
  out.clear();
  inj.Flood(0.5, 0.01, &out);  // 10 ms of wall time at 1000 frames/s
  ASSERT_EQ(out.size(), 10u);
  for (const auto& f : out) EXPECT_GE(f.can_id, 0x200u);
  out.clear();
  inj.Flood(1.5, 0.01, &out);
  EXPECT_TRUE(out.empty());
}

TEST(FaultInjectorTest, LossDuplicateReorderAndDelayAtTheirRates) {
  std::string error;
  FaultInjector inj(*ParseFaultSpec("loss:p=0.1,duplicate:p=0.1,reorder:p=0.1,delay:p=0.1:max=0.05", &error), 7);
  std::vector<can_frame> out;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    inj.Process(i * 0.01, Enc(static_cast<uint16_t>(i * 10), 0, 0, static_cast<uint8_t>(i)), &out);
  }
  const auto& c = inj.counters();
  EXPECT_NEAR(c.lost, 0.1 * n, 0.01 * n);
  EXPECT_GT(c.duplicated, 0.05 * n);
  EXPECT_GT(c.reordered, 0.05 * n);
  EXPECT_GT(c.delayed, 0.05 * n);
  inj.Process(n * 0.01 + 1, {}, &out);  // the delayed ones come out
  // Everything not lost arrives (duplicates twice; one may still wait to be swapped).
  EXPECT_LE(out.size(), n - c.lost + c.duplicated);
  EXPECT_GE(out.size() + 1, n - c.lost + c.duplicated);
  int out_of_order = 0;
  for (size_t i = 1; i < out.size(); ++i) out_of_order += AsEnc(out[i]).timestamp_ms < AsEnc(out[i - 1]).timestamp_ms;
  EXPECT_GT(out_of_order, 0.05 * n);
}

}  // namespace
}  // namespace irslam::sim
