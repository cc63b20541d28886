// Random worlds for the robustness campaign (`irslam-sim generate`, contracts §7):
// rectangular rooms from 3 x 3 to 8 x 7 m with 0-6 pieces of furniture of every
// kind the model knows (against a wall, in a room corner, free, compounds of 2-3
// touching boxes, L shapes), clutter (chair legs and posts of 2-6 cm in groups of
// four), gaps from 0.2 m (impassable) to 1.5 m, boxes closer to a wall than the
// robot can pass, and a start pose anywhere free with any heading (sometimes
// facing a corner or beside a free object). The same seed gives the same world.
//
// Noise profiles (issue 11): `nominal` is the simulator's defaults (a freshly
// calibrated robot); `realistic` and `harsh` draw every magnitude of the error
// envelope uniformly within its range, with a random sign where it has one, so a
// campaign covers the envelope rather than one corner of it. Ranges and where
// they come from: docs/robustness.md.
#ifndef IRSLAM_SIM_GENERATOR_H_
#define IRSLAM_SIM_GENERATOR_H_

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <string_view>

#include "sim/world.h"

namespace irslam::sim {

enum class NoiseProfile { kNominal, kRealistic, kHarsh };
std::optional<NoiseProfile> ParseNoiseProfile(std::string_view name);
const char* ToString(NoiseProfile p);

// The noise of one run drawn from a profile.
SimNoise DrawNoise(NoiseProfile profile, std::mt19937_64* rng);

// The world for a seed (its "seed" is the seed, its name says profile and seed).
World GenerateWorld(uint64_t seed, NoiseProfile profile);

// The world as a world file (contracts §1), every noise key written.
nlohmann::json WorldToJson(const World& w);

// The smallest distance from the robot's centre at (x, y) to any wall or box.
double ClearanceAt(const World& w, double x, double y);

}  // namespace irslam::sim

#endif  // IRSLAM_SIM_GENERATOR_H_
