// One input device of AMBF's input_devices.yaml, as teleoperation uses it: which
// device, how its motion maps onto a simulated body, and how the body's motion comes
// back as force. Units SI; angles in radians.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "afhub/shm_layout/geometry.hpp"

namespace afhub::teleop {

struct Gains {
  double p{0.0};
  double d{0.0};
};

// AMBF's "controller gain": P and D, linear (N/m, N s/m) and angular (N m/rad, N m s/rad).
struct CartesianGains {
  Gains linear;
  Gains angular;
};

// Button indices (bit i of DeviceState::buttons); -1: none. AMBF's keys and defaults:
// a1 clutches and a2 moves the camera (and clutches too) in the default mode; in the
// gripper jaw mode a1 opens and a2 closes the jaw; g1 closes the gripper while held.
struct ButtonMapping {
  int clutch{0};     // a1
  int camera{1};     // a2
  int gripper{-1};   // g1
  int next_mode{2};  // "next mode"
  int prev_mode{3};  // "prev mode"
};

// A frame in the world: position and fixed-axis roll, pitch, yaw, as ADF writes them.
struct Placement {
  Vec3 position_m;
  Vec3 rpy_rad;
};

struct InputDeviceSpec {
  std::string identifier;           // the block's key, "Novint Falcon1"
  std::string where;                // file:line:col of the block
  std::string hardware_name;        // which device: "Falcon", "MTMR", ...
  double haptic_gain_linear{0.0};   // N/m of body-to-proxy distance, in the world
  double haptic_gain_angular{0.0};  // N m/rad
  double workspace_scale{10.0};     // world metres per device metre (AMBF's default 10)
  Placement location;               // the device frame in the world
  bool location_given{false};
  Vec3 orientation_offset_rpy;  // rotates the device's axes before they are mapped
  std::optional<CartesianGains> controller_gain;  // absent: the root body's own gains
  double deadband_n{0.0};                         // device forces below it are not rendered
  std::optional<double> max_force_n;              // absent: the device's own maximum
  // AMBF reads "max jerk" and never applies it; afhub takes it as the largest change of
  // the device force per millisecond (N/ms: one step of AMBF's 1 kHz haptic loop), which
  // bounds the jerk the force gives the user's hand.
  std::optional<double> max_jerk_n_per_ms;
  ButtonMapping buttons;
  std::string root_link;            // empty: the simulated multibody's root body
  std::string simulated_multibody;  // resolved against the file's folder; empty: none
  std::string simulated_multibody_where;
  bool enable_joint_control{true};
  std::vector<std::string> pair_cameras;  // for the viewer: motion is w.r.t. the first
  bool visible{false};                    // AMBF's marker at the proxy (for the viewer)
  double visible_size_m{0.0};
};

}  // namespace afhub::teleop
