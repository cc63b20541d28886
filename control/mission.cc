#include "control/mission.h"

#include <algorithm>
#include <cmath>

namespace irslam::control {

const char* ToString(MissionState s) {
  switch (s) {
    case MissionState::kIdle: return "idle";
    case MissionState::kWallFollow: return "wall_follow";
    case MissionState::kModel: return "model";
    case MissionState::kGoToP1: return "go_to_p1";
    case MissionState::kContourFollow: return "contour_follow";
    case MissionState::kDone: return "done";
    case MissionState::kFault: return "fault";
  }
  return "?";
}

Mission::Mission(MissionOptions options, WallFollowerOptions wall, const slam::SlamOptions& slam)
    : options_(options),
      geometry_(slam.geometry),
      follower_(wall, slam.mounts, slam.geometry.radius_m) {}

void Mission::Enter(MissionState s, double t, std::string reason) {
  state_ = s;
  reason_ = std::move(reason);
  if (s == MissionState::kWallFollow) {
    follower_.Reset();
    have_anchor_ = false;
    progress_t_ = t;
  }
}

bool Mission::Start(double t, std::string* why) {
  if (state_ == MissionState::kFault) {
    *why = "cannot start while in fault: " + reason_;
    return false;
  }
  if (state_ != MissionState::kIdle && state_ != MissionState::kDone) {
    *why = std::string("already running (") + ToString(state_) + ")";
    return false;
  }
  started_at_ = t;
  last_t_ = t;
  loops_done_ = 0;
  loop_times_.clear();
  Enter(MissionState::kWallFollow, t, "");
  return true;
}

void Mission::Stop(double t) {
  if (state_ == MissionState::kFault) resume_state_ = MissionState::kIdle;
  if (state_ != MissionState::kFault) Enter(MissionState::kIdle, t, "stopped by request");
  last_cmd_ = {};
}

void Mission::SetFault(double /*t*/, const std::string& reason) {
  if (state_ != MissionState::kFault) {
    resume_state_ = state_;
    state_ = MissionState::kFault;
  }
  reason_ = reason;
  last_cmd_ = {};
}

void Mission::ClearFault(double t) {
  if (state_ != MissionState::kFault) return;
  state_ = resume_state_;
  reason_ = "resumed after: " + reason_;
  progress_t_ = t;
}

WheelCommand Mission::ToWheels(const Twist& tw, double dt) {
  const double half = 0.5 * geometry_.wheel_base_m;
  double l = tw.v - tw.omega * half;
  double r = tw.v + tw.omega * half;
  const double vmax = geometry_.max_wheel_speed_mps;
  const double over = std::max({std::abs(l) / vmax, std::abs(r) / vmax, 1.0});
  l /= over;
  r /= over;
  // Acceleration limit, so the wheels do not slip at every mode switch.
  const double dv = options_.max_accel_mps2 * std::max(dt, 1e-3);
  l = std::clamp(l, last_cmd_.left_mps - dv, last_cmd_.left_mps + dv);
  r = std::clamp(r, last_cmd_.right_mps - dv, last_cmd_.right_mps + dv);
  last_cmd_ = {l, r, true};
  return last_cmd_;
}

WheelCommand Mission::Step(double t, const slam::Slam& slam, const RangeScan& scan, bool bumped) {
  const double dt = std::clamp(t - last_t_, 0.0, 0.1);
  last_t_ = t;
  switch (state_) {
    case MissionState::kIdle:
    case MissionState::kDone:
    case MissionState::kFault:
      last_cmd_ = {};
      return {};
    default:
      break;
  }
  if (t - started_at_ > options_.max_time_s) {
    Enter(MissionState::kIdle, t, "mission time limit reached");
    last_cmd_ = {};
    return {};
  }
  if (slam.distance_m() > progress_distance_ + 0.05) {
    progress_distance_ = slam.distance_m();
    progress_t_ = t;
  } else if (t - progress_t_ > options_.progress_timeout_s) {
    Enter(MissionState::kIdle, t, "no progress for " +
                                      std::to_string(static_cast<int>(options_.progress_timeout_s)) +
                                      " s");
    last_cmd_ = {};
    return {};
  }

  if (state_ == MissionState::kWallFollow) {
    const Twist tw = follower_.Step(t, scan, bumped);
    // The loop's anchor: a pose after 1.5 s of steady following, so it lies on
    // the path the robot will come back along.
    if (!follower_.steady()) {
      follow_since_ = -1;
    } else if (follow_since_ < 0) {
      follow_since_ = t;
    }
    if (follow_since_ >= 0 && t - follow_since_ >= 1.5 && !have_anchor_) {
      have_anchor_ = true;
      anchor_ = slam.pose();
      last_pose_ = anchor_;
      turned_since_anchor_ = 0;
      anchor_distance_ = slam.distance_m();
    }
    if (have_anchor_) {
      turned_since_anchor_ += NormalizeAngle(slam.pose().theta - last_pose_.theta);
      last_pose_ = slam.pose();
    }
    if (have_anchor_ && slam.distance_m() - anchor_distance_ > options_.loop_min_distance_m) {
      const Pose2& p = slam.pose();
      const double d = std::hypot(p.x - anchor_.x, p.y - anchor_.y);
      const double a = std::abs(NormalizeAngle(p.theta - anchor_.theta));
      if (d < options_.loop_close_radius_m && a < options_.loop_close_angle_rad) {
        if (turned_since_anchor_ < -M_PI) {
          // With the wall on the right, the room's inside is walked counter-
          // clockwise (+2 pi) and a free object's outside clockwise (-2 pi): this
          // was a free object, not the room. Leave it and find a wall.
          ++objects_left_;
          have_anchor_ = false;
          follower_.Leave(t);
          reason_ = "circled a free object; looking for a wall";
        } else if (++loops_done_ < options_.wall_follow_loops) {
          // Another loop of the room was asked for: keep following from here.
          loop_times_.push_back(t);
          anchor_ = slam.pose();
          anchor_distance_ = slam.distance_m();
          turned_since_anchor_ = 0;
        } else {
          // The room has been walked all round: model it. (Exploration builds on this.)
          loop_times_.push_back(t);
          Enter(MissionState::kModel, t, "wall-following loop closed");
          last_cmd_ = {};
          return {};
        }
      }
    }
    return ToWheels(tw, dt);
  }
  if (state_ == MissionState::kModel) {
    Enter(MissionState::kDone, t, "room modelled");
    last_cmd_ = {};
    return {};
  }
  last_cmd_ = {};
  return {};
}

}  // namespace irslam::control
