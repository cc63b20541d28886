// Fault injection between the simulated controller and the bus (irslam-sim
// --faults SPEC; docs/reliability.md). Pure: robot time and frames in, frames out,
// seeded. SPEC is a comma-separated list of faults, each NAME[:KEY=VALUE...]:
//
//   loss:p=P                    drop each controller frame with probability P
//   burst:every=S:len=S         drop every frame for len seconds, every `every` seconds
//   corrupt:p=P                 flip one random payload bit of a frame with probability P
//   duplicate:p=P               send a frame twice
//   reorder:p=P                 swap a frame with the one after it
//   delay:p=P:max=S             hold a frame back up to max seconds (it arrives late)
//   silence:at=T:for=S[:reset=1]  the controller sends nothing in [T, T+S]; with
//                               reset=1 it restarted meanwhile: clock, counts and
//                               sequence numbers start again from zero
//   flood:at=T:for=S[:rate=R]   foreign-id frames at R per wall second (default
//                               8000: a 1 Mbit/s bus at full load), ids 0x200-0x7FF
//   stuck_ir:sensor=I:at=T[:for=S]  sensor I's raw value stays what it was at T
//   encoder_glitch:at=T:counts=N[:wheel=left|right|both]  the count jumps by N and stays
//   kidnap:at=T:x=X:y=Y[:theta=A]  the robot is lifted and put down at (X, Y, A) (world
//                               frame, metres and radians): the true pose jumps, the
//                               encoders count no motion for the jump (issue 14)
//
// Times are robot seconds. Probabilities apply to the controller's frames
// (ENCODER, CTRL_STATUS, IR_A, IR_B). Each fault's keys are an option table
// (types/options.h) below: names, types and bounds are checked in one place
// (io/option_json.h), unknown keys are an error.
#ifndef IRSLAM_SIM_FAULTS_H_
#define IRSLAM_SIM_FAULTS_H_

#include <linux/can.h>

#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "types/geometry.h"
#include "types/options.h"

namespace irslam::sim {

// The keys of each fault (defaults as documented above; the keys a fault needs
// are listed by ParseFaultSpec).
struct ChanceFaultParams {  // loss, corrupt, duplicate, reorder
  double p = 0;
};
struct BurstFaultParams {
  double every = 0, len = 0;
};
struct DelayFaultParams {
  double p = 0, max = 0.02;
};
struct SilenceFaultParams {
  double at = 0, for_s = 0;
  int reset = 0;
};
struct FloodFaultParams {
  double at = 0, for_s = 0, rate = 8000;
};
struct StuckIrFaultParams {
  int sensor = 0;
  double at = 0, for_s = 1e9;
};
struct EncoderGlitchFaultParams {
  double at = 0;
  int counts = 0;
  std::string wheel = "left";
};
struct KidnapFaultParams {
  double at = 0, x = 0, y = 0, theta = 0;
};
options::Table<ChanceFaultParams> ChanceFaultKeys();
options::Table<BurstFaultParams> BurstFaultKeys();
options::Table<DelayFaultParams> DelayFaultKeys();
options::Table<SilenceFaultParams> SilenceFaultKeys();
options::Table<FloodFaultParams> FloodFaultKeys();
options::Table<StuckIrFaultParams> StuckIrFaultKeys();
options::Table<EncoderGlitchFaultParams> EncoderGlitchFaultKeys();
options::Table<KidnapFaultParams> KidnapFaultKeys();

struct FaultSpec {
  double loss_p = 0;
  double burst_every_s = 0, burst_len_s = 0;
  double corrupt_p = 0;
  double duplicate_p = 0;
  double reorder_p = 0;
  double delay_p = 0, delay_max_s = 0;
  struct Window {
    double at = 0, len = 0;
    bool contains(double t) const { return len > 0 && t >= at && t < at + len; }
  };
  std::vector<Window> silence;
  std::vector<bool> silence_reset;
  std::vector<Window> flood;
  double flood_rate = 8000;
  struct Stuck {
    int sensor = 0;
    Window when;
  };
  std::vector<Stuck> stuck_ir;
  struct Glitch {
    double at = 0;
    int counts = 0;
    bool left = true, right = false;
  };
  std::vector<Glitch> encoder_glitch;
  // The robot's true pose is set to `to` at robot time `at` (the simulator's,
  // not the bus's: FaultInjector::TakeKidnap hands it over).
  struct Kidnap {
    double at = 0;
    Pose2 to;
  };
  std::vector<Kidnap> kidnap;
  bool any() const;
};

// Parses SPEC; nullopt and a one-line *error naming the bad part.
std::optional<FaultSpec> ParseFaultSpec(const std::string& spec, std::string* error);

struct FaultCounters {
  uint64_t lost = 0, corrupted = 0, duplicated = 0, reordered = 0, delayed = 0, silenced = 0,
           flooded = 0, stuck = 0, glitched = 0, kidnapped = 0;
};

class FaultInjector {
 public:
  FaultInjector(FaultSpec spec, uint64_t seed);

  // The controller's frames of robot time t in, what reaches the bus now out
  // (appended to *out; held-back frames come out on a later call).
  void Process(double t, const std::vector<can_frame>& in, std::vector<can_frame>* out);
  // Foreign frames of a flood active at robot time t, for wall_dt seconds of wall time.
  void Flood(double t, double wall_dt, std::vector<can_frame>* out);

  // A kidnap due at robot time t (its time reached and not yet taken), once
  // each, in time order: the caller teleports the simulated robot
  // (SimController::Teleport) before advancing it to t.
  std::optional<Pose2> TakeKidnap(double t);

  const FaultCounters& counters() const { return counters_; }

 private:
  void Rewrite(double t, can_frame* f);

  FaultSpec spec_;
  std::mt19937_64 rng_;
  FaultCounters counters_;
  std::optional<can_frame> swap_;  // a frame waiting to be sent after the next one
  std::vector<std::pair<double, can_frame>> delayed_;
  // Controller reset: what the restarted controller subtracts.
  bool reset_pending_ = false, reset_done_ = false;
  uint16_t stamp_base_ = 0, left_base_ = 0, right_base_ = 0;
  uint8_t enc_seq_base_ = 0, status_seq_base_ = 0, ir_seq_base_ = 0;
  unsigned bases_pending_ = 0;  // bit 0 encoder, 1 status, 2 IR: origins still to take
  std::vector<std::optional<uint16_t>> stuck_value_;
  double flood_carry_ = 0;
  uint32_t flood_id_ = 0x200;
  size_t kidnaps_taken_ = 0;  // spec_.kidnap is sorted by time
};

}  // namespace irslam::sim

#endif  // IRSLAM_SIM_FAULTS_H_
