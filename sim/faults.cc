#include "sim/faults.h"

#include <cmath>
#include <map>
#include <sstream>

#include "proto/codec.h"

namespace irslam::sim {

bool FaultSpec::any() const {
  return loss_p > 0 || burst_len_s > 0 || corrupt_p > 0 || duplicate_p > 0 || reorder_p > 0 || delay_p > 0 ||
         !silence.empty() || !flood.empty() || !stuck_ir.empty() || !encoder_glitch.empty();
}

std::optional<FaultSpec> ParseFaultSpec(const std::string& spec, std::string* error) {
  FaultSpec f;
  std::stringstream items(spec);
  std::string item;
  while (std::getline(items, item, ',')) {
    if (item.empty()) continue;
    std::stringstream parts(item);
    std::string name, kv;
    std::getline(parts, name, ':');
    std::map<std::string, double> args;
    std::map<std::string, std::string> words;
    while (std::getline(parts, kv, ':')) {
      const auto eq = kv.find('=');
      if (eq == std::string::npos) {
        *error = "faults: '" + item + "': expected KEY=VALUE, got '" + kv + "'";
        return std::nullopt;
      }
      const std::string key = kv.substr(0, eq), value = kv.substr(eq + 1);
      char* end = nullptr;
      const double d = std::strtod(value.c_str(), &end);
      if (end != value.c_str() && *end == '\0' && std::isfinite(d) && d >= 0) {
        args[key] = d;
      } else {
        words[key] = value;
      }
    }
    // Every key of an item must be one it knows, with a number (or a known word).
    const auto take = [&](const char* key, double def, bool required, double hi) -> std::optional<double> {
      auto it = args.find(key);
      if (it == args.end()) {
        if (words.count(key)) {
          *error = "faults: '" + item + "': " + key + " must be a number >= 0";
          return std::nullopt;
        }
        if (required) {
          *error = "faults: '" + item + "': needs " + key + "=";
          return std::nullopt;
        }
        return def;
      }
      const double v = it->second;
      args.erase(it);
      if (v > hi) {
        std::ostringstream os;
        os << "faults: '" << item << "': " << key << " must be at most " << hi;
        *error = os.str();
        return std::nullopt;
      }
      return v;
    };
    std::optional<double> a, b, c;
    if (name == "loss") {
      if (!(a = take("p", 0, true, 1))) return std::nullopt;
      f.loss_p = *a;
    } else if (name == "burst") {
      if (!(a = take("every", 0, true, 1e6)) || !(b = take("len", 0, true, 1e6))) return std::nullopt;
      f.burst_every_s = *a;
      f.burst_len_s = *b;
    } else if (name == "corrupt") {
      if (!(a = take("p", 0, true, 1))) return std::nullopt;
      f.corrupt_p = *a;
    } else if (name == "duplicate") {
      if (!(a = take("p", 0, true, 1))) return std::nullopt;
      f.duplicate_p = *a;
    } else if (name == "reorder") {
      if (!(a = take("p", 0, true, 1))) return std::nullopt;
      f.reorder_p = *a;
    } else if (name == "delay") {
      if (!(a = take("p", 0, true, 1)) || !(b = take("max", 0.02, false, 10))) return std::nullopt;
      f.delay_p = *a;
      f.delay_max_s = *b;
    } else if (name == "silence") {
      if (!(a = take("at", 0, true, 1e6)) || !(b = take("for", 0, true, 1e6)) || !(c = take("reset", 0, false, 1))) {
        return std::nullopt;
      }
      f.silence.push_back({*a, *b});
      f.silence_reset.push_back(*c > 0);
    } else if (name == "flood") {
      if (!(a = take("at", 0, true, 1e6)) || !(b = take("for", 0, true, 1e6)) ||
          !(c = take("rate", f.flood_rate, false, 1e6))) {
        return std::nullopt;
      }
      f.flood.push_back({*a, *b});
      f.flood_rate = *c;
    } else if (name == "stuck_ir") {
      if (!(a = take("sensor", 0, true, 6)) || !(b = take("at", 0, true, 1e6)) || !(c = take("for", 1e9, false, 1e9))) {
        return std::nullopt;
      }
      f.stuck_ir.push_back({static_cast<int>(*a), {*b, *c}});
    } else if (name == "encoder_glitch") {
      if (!(a = take("at", 0, true, 1e6)) || !(b = take("counts", 0, true, 30000))) return std::nullopt;
      FaultSpec::Glitch g{*a, static_cast<int>(*b), true, false};
      if (auto w = words.find("wheel"); w != words.end()) {
        g.left = w->second == "left" || w->second == "both";
        g.right = w->second == "right" || w->second == "both";
        if (!g.left && !g.right) {
          *error = "faults: '" + item + "': wheel must be left, right or both";
          return std::nullopt;
        }
        words.erase(w);
      }
      f.encoder_glitch.push_back(g);
    } else {
      *error = "faults: unknown fault '" + name +
               "' (known: loss, burst, corrupt, duplicate, reorder, delay, silence, flood, stuck_ir, encoder_glitch)";
      return std::nullopt;
    }
    if (!args.empty() || !words.empty()) {
      *error = "faults: '" + item + "': unknown key '" + (args.empty() ? words.begin()->first : args.begin()->first) + "'";
      return std::nullopt;
    }
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
