// The Novint Falcon's kinematics (a delta robot; R. E. Stamper's model, with the
// dimensions libnifalcon measured), in its kinematic frame: metres, origin at the
// centre of the base, x right, y up, z out of the device towards the user. The
// device frame FalconDevice publishes is centred on the workspace (kWorkspaceCentre).
// Pure math: no allocation, no I/O.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

namespace afhub::devices::falcon {

using Vec = std::array<double, 3>;
using Matrix = std::array<Vec, 3>;        // row-major
using LegAngles = std::array<double, 3>;  // theta1 (the driven thigh) per leg, radians

// The middle of the reachable volume, where the grip rests when centred.
inline constexpr Vec kWorkspaceCentre{0.0, 0.0, 0.11};
// No pose of the device is farther than this from the centre, metres.
inline constexpr double kReachLimit = 0.08;
// The largest torque the 16-bit motor command carries (motor = -10000 * torque).
inline constexpr double kMotorPerTorque = -10000.0;
inline constexpr double kMaxTorque = 32767.0 / 10000.0;

// Encoder counts to the thigh angle, and back (not rounded).
double encoder_to_angle(std::int16_t counts);
double angle_to_encoder(double theta1_rad);

// Closed-form inverse kinematics: the thigh angles that put the grip at `position`;
// nullopt when no leg configuration reaches it.
std::optional<LegAngles> inverse(const Vec& position);

// d(theta1)/d(position) at `position` (rows: legs), from the closed form; nullopt out
// of reach or at a singularity.
std::optional<Matrix> angle_jacobian(const Vec& position);
// The velocity Jacobian d(position)/d(theta1) (its inverse): velocity = J * leg rates,
// torques = J^T * force.
std::optional<Matrix> jacobian(const Vec& position);

// Forward kinematics by Newton-Raphson on the inverse. Stateful: each solve starts
// from the previous answer, so at 1 kHz it converges in one or two steps.
class ForwardSolver {
 public:
  explicit ForwardSolver(const Vec& start = kWorkspaceCentre) : guess_(start) {}
  // The position whose thigh angles are `angles`, within 1e-9 m; nullopt (and the
  // previous answer kept as the next start) when none within kReachLimit is found.
  std::optional<Vec> solve(const LegAngles& angles);
  const Vec& last() const { return guess_; }
  void reset(const Vec& start = kWorkspaceCentre) { guess_ = start; }

 private:
  Vec guess_;
};

struct Torques {
  Vec torque_nm{};    // per leg
  double scale{1.0};  // < 1 when all three were scaled down to fit max_torque
};

// tau = J^T F at `position`. When any |tau| exceeds `max_torque` all three are scaled
// by the same factor, so the force keeps its direction. nullopt out of reach.
std::optional<Torques> force_to_torques(const Vec& position, const Vec& force_n,
                                        double max_torque = kMaxTorque);

// Motor commands (-10000 per N m), saturated to the int16 range, never wrapped.
std::array<std::int16_t, 3> torques_to_motors(const Vec& torque_nm);

}  // namespace afhub::devices::falcon
