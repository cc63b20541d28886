#include "sim/faults.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <sstream>
#include <string_view>

#include "io/option_json.h"
#include "proto/codec.h"

namespace irslam::sim {

bool FaultSpec::any() const {
  return loss_p > 0 || burst_len_s > 0 || corrupt_p > 0 || duplicate_p > 0 || reorder_p > 0 || delay_p > 0 ||
         !silence.empty() || !flood.empty() || !stuck_ir.empty() || !encoder_glitch.empty() ||
         !kidnap.empty();
}

namespace {

constexpr double kMaxTimeS = 1e6;  // robot seconds

// One item of SPEC as written: NAME and its KEY=VALUE pairs in order.
struct Item {
  std::string text, name;
  std::vector<std::pair<std::string, std::string>> values;
};

bool SplitItem(const std::string& text, Item* item, std::string* error) {
  item->text = text;
  std::stringstream parts(text);
  std::getline(parts, item->name, ':');
  std::string kv;
  while (std::getline(parts, kv, ':')) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos) {
      *error = "faults: '" + text + "': expected KEY=VALUE, got '" + kv + "'";
      return false;
    }
    item->values.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
  }
  return true;
}

// A value as the option table reads it: a number when the whole text is one, else a word.
nlohmann::json ValueJson(const std::string& text) {
  char* end = nullptr;
  const double d = std::strtod(text.c_str(), &end);
  if (!text.empty() && *end == '\0' && std::isfinite(d)) return d;
  return text;
}

// Sets *params from the item through the fault's key table: the required keys
// given, every key in the table, every value of its key's type and within its
// bounds (io/option_json.h). The error names the item and the key.
template <class P>
bool ReadParams(const Item& item, options::Table<P> keys,
                std::initializer_list<std::string_view> required, P* params, std::string* error) {
  const std::string where = "faults: '" + item.text + "': ";
  for (const std::string_view key : required) {
    if (std::none_of(item.values.begin(), item.values.end(),
                     [&](const auto& kv) { return kv.first == key; })) {
      *error = where + "needs " + std::string(key) + "=";
      return false;
    }
  }
  const std::vector<options::Entry> entries = options::Bind(params, keys);
  for (const auto& kv : item.values) {
    const std::string& key = kv.first;
    const auto e = std::find_if(entries.begin(), entries.end(),
                                [&](const options::Entry& x) { return x.name == key; });
    if (e == entries.end()) {
      *error = where + "unknown key '" + key + "'";
      return false;
    }
    const std::string what = options::ReadEntry(ValueJson(kv.second), *e);
    if (!what.empty()) {
      *error = where + key + what;
      return false;
    }
  }
  return true;
}

double& ChanceOf(const std::string& name, FaultSpec* f) {
  if (name == "loss") return f->loss_p;
  if (name == "corrupt") return f->corrupt_p;
  if (name == "duplicate") return f->duplicate_p;
  return f->reorder_p;
}

bool AddFault(const Item& item, FaultSpec* f, std::string* error) {
  const std::string& n = item.name;
  if (n == "loss" || n == "corrupt" || n == "duplicate" || n == "reorder") {
    ChanceFaultParams c;
    if (!ReadParams(item, ChanceFaultKeys(), {"p"}, &c, error)) return false;
    ChanceOf(n, f) = c.p;
  } else if (n == "burst") {
    BurstFaultParams b;
    if (!ReadParams(item, BurstFaultKeys(), {"every", "len"}, &b, error)) return false;
    f->burst_every_s = b.every;
    f->burst_len_s = b.len;
  } else if (n == "delay") {
    DelayFaultParams d;
    if (!ReadParams(item, DelayFaultKeys(), {"p"}, &d, error)) return false;
    f->delay_p = d.p;
    f->delay_max_s = d.max;
  } else if (n == "silence") {
    SilenceFaultParams s;
    if (!ReadParams(item, SilenceFaultKeys(), {"at", "for"}, &s, error)) return false;
    f->silence.push_back({s.at, s.for_s});
    f->silence_reset.push_back(s.reset > 0);
  } else if (n == "flood") {
    FloodFaultParams fl;
    fl.rate = f->flood_rate;  // a flood without rate= keeps an earlier one's
    if (!ReadParams(item, FloodFaultKeys(), {"at", "for"}, &fl, error)) return false;
    f->flood.push_back({fl.at, fl.for_s});
    f->flood_rate = fl.rate;
  } else if (n == "stuck_ir") {
    StuckIrFaultParams st;
    if (!ReadParams(item, StuckIrFaultKeys(), {"sensor", "at"}, &st, error)) return false;
    f->stuck_ir.push_back({st.sensor, {st.at, st.for_s}});
  } else if (n == "encoder_glitch") {
    EncoderGlitchFaultParams g;
    if (!ReadParams(item, EncoderGlitchFaultKeys(), {"at", "counts"}, &g, error)) return false;
    const bool left = g.wheel == "left" || g.wheel == "both";
    const bool right = g.wheel == "right" || g.wheel == "both";
    if (!left && !right) {
      *error = "faults: '" + item.text + "': wheel must be left, right or both";
      return false;
    }
    f->encoder_glitch.push_back({g.at, g.counts, left, right});
  } else if (n == "kidnap") {
    KidnapFaultParams k;
    if (!ReadParams(item, KidnapFaultKeys(), {"at", "x", "y"}, &k, error)) return false;
    f->kidnap.push_back({k.at, {k.x, k.y, NormalizeAngle(k.theta)}});
    std::stable_sort(f->kidnap.begin(), f->kidnap.end(),
                     [](const FaultSpec::Kidnap& a, const FaultSpec::Kidnap& b) { return a.at < b.at; });
  } else {
    *error = "faults: unknown fault '" + n +
             "' (known: loss, burst, corrupt, duplicate, reorder, delay, silence, flood, stuck_ir, "
             "encoder_glitch, kidnap)";
    return false;
  }
  return true;
}

}  // namespace

options::Table<ChanceFaultParams> ChanceFaultKeys() {
  static constexpr options::Key<ChanceFaultParams> kKeys[] = {
      {"p", &ChanceFaultParams::p, 0, 1, "", "probability per controller frame"},
  };
  return kKeys;
}

options::Table<BurstFaultParams> BurstFaultKeys() {
  using B = BurstFaultParams;
  static constexpr options::Key<B> kKeys[] = {
      {"every", &B::every, 0, kMaxTimeS, "s", "a burst starts this often"},
      {"len", &B::len, 0, kMaxTimeS, "s", "every frame is dropped for this long"},
  };
  return kKeys;
}

options::Table<DelayFaultParams> DelayFaultKeys() {
  using D = DelayFaultParams;
  static constexpr options::Key<D> kKeys[] = {
      {"p", &D::p, 0, 1, "", "probability per controller frame"},
      {"max", &D::max, 0, 10, "s", "a delayed frame is held back up to this long"},
  };
  return kKeys;
}

options::Table<SilenceFaultParams> SilenceFaultKeys() {
  using S = SilenceFaultParams;
  static constexpr options::Key<S> kKeys[] = {
      {"at", &S::at, 0, kMaxTimeS, "s", "the controller falls silent at this robot time"},
      {"for", &S::for_s, 0, kMaxTimeS, "s", "for this long"},
      {"reset", &S::reset, 0, 1, "", "1: it restarted meanwhile (clock, counts, sequences from 0)"},
  };
  return kKeys;
}

options::Table<FloodFaultParams> FloodFaultKeys() {
  using F = FloodFaultParams;
  static constexpr options::Key<F> kKeys[] = {
      {"at", &F::at, 0, kMaxTimeS, "s", "the flood starts at this robot time"},
      {"for", &F::for_s, 0, kMaxTimeS, "s", "and lasts this long"},
      {"rate", &F::rate, 0, 1e6, "1/s", "foreign frames per wall second"},
  };
  return kKeys;
}

options::Table<StuckIrFaultParams> StuckIrFaultKeys() {
  using S = StuckIrFaultParams;
  static constexpr options::Key<S> kKeys[] = {
      {"sensor", &S::sensor, 0, 6, "", "the IR sensor whose raw value sticks"},
      {"at", &S::at, 0, kMaxTimeS, "s", "it keeps the value it had at this robot time"},
      {"for", &S::for_s, 0, 1e9, "s", "for this long"},
  };
  return kKeys;
}

options::Table<EncoderGlitchFaultParams> EncoderGlitchFaultKeys() {
  using G = EncoderGlitchFaultParams;
  static constexpr options::Key<G> kKeys[] = {
      {"at", &G::at, 0, kMaxTimeS, "s", "the count jumps at this robot time"},
      {"counts", &G::counts, 0, 30000, "", "by this many counts, and stays"},
      {"wheel", &G::wheel, 0, 0, "", "left, right or both"},
  };
  return kKeys;
}

options::Table<KidnapFaultParams> KidnapFaultKeys() {
  using K = KidnapFaultParams;
  static constexpr options::Key<K> kKeys[] = {
      {"at", &K::at, 0, kMaxTimeS, "s", "the robot is lifted at this robot time"},
      {"x", &K::x, -1000, 1000, "m", "and put down here (world frame)"},
      {"y", &K::y, -1000, 1000, "m", "(world frame)"},
      {"theta", &K::theta, -10, 10, "rad", "heading when put down"},
  };
  return kKeys;
}

std::optional<Pose2> FaultInjector::TakeKidnap(double t) {
  if (kidnaps_taken_ >= spec_.kidnap.size() || spec_.kidnap[kidnaps_taken_].at > t) return std::nullopt;
  ++counters_.kidnapped;
  return spec_.kidnap[kidnaps_taken_++].to;
}

std::optional<FaultSpec> ParseFaultSpec(const std::string& spec, std::string* error) {
  FaultSpec f;
  std::stringstream items(spec);
  std::string text;
  while (std::getline(items, text, ',')) {
    if (text.empty()) continue;
    Item item;
    if (!SplitItem(text, &item, error) || !AddFault(item, &f, error)) return std::nullopt;
  }
  return f;
}

FaultInjector::FaultInjector(FaultSpec spec, uint64_t seed)
    : spec_(std::move(spec)), rng_(seed ^ 0xfa17u), stuck_value_(spec_.stuck_ir.size()) {}

void FaultInjector::Rewrite(double t, can_frame* f) {
  proto::DecodeResult d = proto::Decode(*f);
  if (!d.ok()) return;
  bool changed = false;
  if (reset_pending_) {
    // The first frame after a reset-silence: the restarted controller's origin.
    reset_pending_ = false;
    reset_done_ = true;
    uint16_t stamp = 0;
    if (auto* e = std::get_if<proto::EncoderCounts>(&d.message)) stamp = e->timestamp_ms;
    if (auto* s = std::get_if<proto::ControllerStatus>(&d.message)) stamp = s->timestamp_ms;
    if (auto* a = std::get_if<proto::IrA>(&d.message)) stamp = a->timestamp_ms;
    stamp_base_ = static_cast<uint16_t>(stamp - 5);  // 5 ms after its boot
    left_base_ = right_base_ = 0;
    enc_seq_base_ = status_seq_base_ = ir_seq_base_ = 0;
    bases_pending_ = 0x7;
  }
  if (reset_done_) {
    if (auto* e = std::get_if<proto::EncoderCounts>(&d.message)) {
      if (bases_pending_ & 1) {
        left_base_ = e->left;
        right_base_ = e->right;
        enc_seq_base_ = e->seq;
        bases_pending_ &= ~1u;
      }
      e->timestamp_ms = static_cast<uint16_t>(e->timestamp_ms - stamp_base_);
      e->left = static_cast<uint16_t>(e->left - left_base_);
      e->right = static_cast<uint16_t>(e->right - right_base_);
      e->seq = static_cast<uint8_t>(e->seq - enc_seq_base_);
    } else if (auto* s = std::get_if<proto::ControllerStatus>(&d.message)) {
      if (bases_pending_ & 2) {
        status_seq_base_ = s->seq;
        bases_pending_ &= ~2u;
      }
      s->timestamp_ms = static_cast<uint16_t>(s->timestamp_ms - stamp_base_);
      s->seq = static_cast<uint8_t>(s->seq - status_seq_base_);
    } else if (auto* a = std::get_if<proto::IrA>(&d.message)) {
      if (bases_pending_ & 4) {
        ir_seq_base_ = a->seq;
        bases_pending_ &= ~4u;
      }
      a->timestamp_ms = static_cast<uint16_t>(a->timestamp_ms - stamp_base_);
      a->seq = static_cast<uint8_t>(a->seq - ir_seq_base_);
    } else if (auto* b = std::get_if<proto::IrB>(&d.message)) {
      b->seq = static_cast<uint8_t>(b->seq - ir_seq_base_);
    }
    changed = true;
  }
  for (size_t i = 0; i < spec_.stuck_ir.size(); ++i) {
    const auto& st = spec_.stuck_ir[i];
    if (!st.when.contains(t)) continue;
    uint16_t* v = nullptr;
    if (auto* a = std::get_if<proto::IrA>(&d.message); a && st.sensor < 3) v = &a->adc[static_cast<size_t>(st.sensor)];
    if (auto* b = std::get_if<proto::IrB>(&d.message); b && st.sensor >= 3) {
      v = &b->adc[static_cast<size_t>(st.sensor - 3)];
    }
    if (v == nullptr) continue;
    if (!stuck_value_[i]) stuck_value_[i] = *v;
    *v = *stuck_value_[i];
    ++counters_.stuck;
    changed = true;
  }
  if (auto* e = std::get_if<proto::EncoderCounts>(&d.message)) {
    for (const auto& g : spec_.encoder_glitch) {
      if (t < g.at) continue;
      if (g.left) e->left = static_cast<uint16_t>(e->left + g.counts);
      if (g.right) e->right = static_cast<uint16_t>(e->right + g.counts);
      ++counters_.glitched;
      changed = true;
    }
  }
  if (changed) *f = proto::Encode(d.message);
}

void FaultInjector::Process(double t, const std::vector<can_frame>& in, std::vector<can_frame>* out) {
  std::uniform_real_distribution<double> u(0, 1);
  for (can_frame f : in) {
    bool silent = false;
    for (size_t i = 0; i < spec_.silence.size(); ++i) {
      if (spec_.silence[i].contains(t)) {
        silent = true;
        if (spec_.silence_reset[i] && !reset_done_) reset_pending_ = true;
      }
    }
    if (silent) {
      ++counters_.silenced;
      continue;
    }
    Rewrite(t, &f);
    if (spec_.burst_every_s > 0 && std::fmod(t, spec_.burst_every_s) < spec_.burst_len_s) {
      ++counters_.lost;
      continue;
    }
    if (spec_.loss_p > 0 && u(rng_) < spec_.loss_p) {
      ++counters_.lost;
      continue;
    }
    if (spec_.corrupt_p > 0 && f.can_dlc > 0 && u(rng_) < spec_.corrupt_p) {
      std::uniform_int_distribution<int> bit(0, f.can_dlc * 8 - 1);
      const int b = bit(rng_);
      f.data[b / 8] ^= static_cast<uint8_t>(1u << (b % 8));
      ++counters_.corrupted;
    }
    if (spec_.delay_p > 0 && u(rng_) < spec_.delay_p) {
      delayed_.emplace_back(t + u(rng_) * spec_.delay_max_s, f);
      ++counters_.delayed;
      continue;
    }
    if (spec_.reorder_p > 0 && !swap_ && u(rng_) < spec_.reorder_p) {
      swap_ = f;  // goes out after the next frame
      ++counters_.reordered;
      continue;
    }
    out->push_back(f);
    if (spec_.duplicate_p > 0 && u(rng_) < spec_.duplicate_p) {
      out->push_back(f);
      ++counters_.duplicated;
    }
    if (swap_) {
      out->push_back(*swap_);
      swap_.reset();
    }
  }
  for (size_t i = 0; i < delayed_.size();) {
    if (delayed_[i].first <= t) {
      out->push_back(delayed_[i].second);
      delayed_.erase(delayed_.begin() + static_cast<std::ptrdiff_t>(i));
    } else {
      ++i;
    }
  }
}

void FaultInjector::Flood(double t, double wall_dt, std::vector<can_frame>* out) {
  bool on = false;
  for (const auto& w : spec_.flood) on |= w.contains(t);
  if (!on) {
    flood_carry_ = 0;
    return;
  }
  flood_carry_ += spec_.flood_rate * wall_dt;
  std::uniform_int_distribution<int> byte(0, 255);
  for (; flood_carry_ >= 1; flood_carry_ -= 1) {
    can_frame f{};
    f.can_id = flood_id_;
    flood_id_ = flood_id_ >= 0x7FF ? 0x200 : flood_id_ + 1;
    f.can_dlc = 8;
    for (auto& b : f.data) b = static_cast<uint8_t>(byte(rng_));
    out->push_back(f);
    ++counters_.flooded;
  }
}

}  // namespace irslam::sim
