#include "afhub/devices/falcon_kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace afhub::devices::falcon {
namespace {

// libnifalcon's FalconGeometry.h (after Stamper, p. 30), metres: a thigh, b shin
// parallelogram side, c and f the effector's offsets, d and e the joint blocks, r and s
// each leg base's offset from the centre.
constexpr double kA = 0.060;
constexpr double kB = 0.1025;
constexpr double kC = 0.01443;
constexpr double kD = 0.01125;
constexpr double kE = 0.01125;
constexpr double kF = -0.025;
constexpr double kR = 0.040;
constexpr double kS = -0.02309;
// The legs' directions; the whole device is tilted 15 degrees from the desk.
constexpr double kPi = std::numbers::pi;
constexpr std::array<double, 3> kPhi{kPi / 2 + kPi / 12, -kPi / 6 + kPi / 12,
                                     -5 * kPi / 6 + kPi / 12};

// Encoder: 320 slots, four counts each, on a 14.25 mm shaft driving a 110 mm arc; 35
// degrees at count 0.
constexpr double kDegreesPerCount = (0.01425 * kPi / 1280.0) / (kPi * 0.110 / 360.0);
constexpr double kDegreesAtZero = 35.0;

struct Leg {
  double theta1;
  double theta2;
  double theta3;
};

// The position in leg i's own (u, v, w) frame.
Vec to_leg_frame(std::size_t leg, const Vec& p) {
  const double c = std::cos(kPhi[leg]);
  const double s = std::sin(kPhi[leg]);
  return {c * p[0] + s * p[1] - kR, -s * p[0] + c * p[1] - kS, p[2]};
}

// In the leg frame: u = a cos t1 + L cos t2 - c, w = a sin t1 + L sin t2,
// v = b cos t3 - f, with L = d + e + b sin t3. Solved by the half-angle substitution.
std::optional<Leg> leg_inverse(std::size_t leg, const Vec& p) {
  const Vec uvw = to_leg_frame(leg, p);
  const double cos3 = (uvw[1] + kF) / kB;
  if (!(std::abs(cos3) <= 1.0)) return std::nullopt;  // also refuses NaN
  const double theta3 = std::acos(cos3);
  const double length = kD + kE + kB * std::sin(theta3);
  const double u = uvw[0] + kC;
  const double w = uvw[2];
  const double k = u * u + kA * kA + w * w - length * length;
  const double l2 = k + 2 * kA * u;
  const double l1 = -4 * kA * w;
  const double l0 = k - 2 * kA * u;
  const double discriminant = l1 * l1 - 4 * l2 * l0;
  if (!(discriminant >= 0.0) || std::abs(l2) < 1e-15) return std::nullopt;
  // The root of the Falcon's assembly (elbows out).
  const double t = (-l1 - std::sqrt(discriminant)) / (2 * l2);
  const double theta1 = 2 * std::atan(t);
  const double theta2 = std::atan2(w - kA * std::sin(theta1), u - kA * std::cos(theta1));
  return Leg{theta1, theta2, theta3};
}

std::optional<Matrix> invert(const Matrix& m) {
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  if (!(std::abs(det) > 1e-300) || !std::isfinite(det)) return std::nullopt;
  Matrix out{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      // Cofactor of (j, i) over the determinant: the adjugate's transpose.
      const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
      out[i][j] = (m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]) / det;
    }
  }
  return out;
}

double norm(const Vec& v) {
  return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

}  // namespace

double encoder_to_angle(std::int16_t counts) {
  return (counts * kDegreesPerCount + kDegreesAtZero) * kPi / 180.0;
}

double angle_to_encoder(double theta1_rad) {
  return (theta1_rad * 180.0 / kPi - kDegreesAtZero) / kDegreesPerCount;
}

std::optional<LegAngles> inverse(const Vec& position) {
  LegAngles out{};
  for (std::size_t leg = 0; leg < 3; ++leg) {
    const auto solved = leg_inverse(leg, position);
    if (!solved) return std::nullopt;
    out[leg] = solved->theta1;
  }
  return out;
}

// Differentiating the leg equations and eliminating t2 and t3:
// a sin(t2 - t1) sin t3 dt1 = cos t2 sin t3 du + cos t3 dv + sin t2 sin t3 dw.
std::optional<Matrix> angle_jacobian(const Vec& position) {
  Matrix out{};
  for (std::size_t leg = 0; leg < 3; ++leg) {
    const auto solved = leg_inverse(leg, position);
    if (!solved) return std::nullopt;
    const double s3 = std::sin(solved->theta3);
    const double c3 = std::cos(solved->theta3);
    const double s2 = std::sin(solved->theta2);
    const double c2 = std::cos(solved->theta2);
    const double den = kA * std::sin(solved->theta2 - solved->theta1) * s3;
    if (std::abs(den) < 1e-12) return std::nullopt;
    const double du = c2 * s3 / den;
    const double dv = c3 / den;
    const double dw = s2 * s3 / den;
    // du = cos(phi) dx + sin(phi) dy, dv = -sin(phi) dx + cos(phi) dy, dw = dz.
    const double c = std::cos(kPhi[leg]);
    const double s = std::sin(kPhi[leg]);
    out[leg] = {du * c - dv * s, du * s + dv * c, dw};
  }
  return out;
}

std::optional<Matrix> jacobian(const Vec& position) {
  const auto rates = angle_jacobian(position);
  if (!rates) return std::nullopt;
  return invert(*rates);
}

namespace {

// Damped Newton from `p`: steps of at most kMaxStep, halved until the angle error falls.
std::optional<Vec> newton(Vec p, const LegAngles& angles) {
  constexpr int kMaxIterations = 60;
  constexpr double kTolerance = 1e-9;  // metres per step
  constexpr double kMaxStep = 0.02;    // metres: far jumps leave the reachable volume
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    const auto at = inverse(p);
    const auto j = jacobian(p);
    if (!at || !j) return std::nullopt;
    const Vec error{angles[0] - (*at)[0], angles[1] - (*at)[1], angles[2] - (*at)[2]};
    Vec step{};
    for (int row = 0; row < 3; ++row) {
      step[row] = (*j)[row][0] * error[0] + (*j)[row][1] * error[1] + (*j)[row][2] * error[2];
    }
    double scale = std::min(1.0, kMaxStep / std::max(norm(step), 1e-300));
    bool better = false;
    Vec next{};
    for (int halving = 0; halving < 30 && !better; ++halving) {
      next = {p[0] + scale * step[0], p[1] + scale * step[1], p[2] + scale * step[2]};
      const auto there = inverse(next);
      if (there) {
        const Vec after{angles[0] - (*there)[0], angles[1] - (*there)[1], angles[2] - (*there)[2]};
        better = norm(after) <= norm(error) || norm(step) * scale < kTolerance;
      }
      if (!better) scale *= 0.5;
    }
    if (!better) return std::nullopt;
    p = next;
    if (norm(step) * scale < kTolerance) {
      // A pose this far from the centre is no pose of the device (encoders not homed).
      const Vec offset{p[0] - kWorkspaceCentre[0], p[1] - kWorkspaceCentre[1],
                       p[2] - kWorkspaceCentre[2]};
      if (norm(offset) > kReachLimit) return std::nullopt;
      return p;
    }
  }
  return std::nullopt;
}

}  // namespace

std::optional<Vec> ForwardSolver::solve(const LegAngles& angles) {
  for (double angle : angles) {
    if (!std::isfinite(angle)) return std::nullopt;
  }
  auto found = newton(guess_, angles);
  // A long jump (a reset, lost packets) can strand the warm start: retry from the centre.
  if (!found && guess_ != kWorkspaceCentre) found = newton(kWorkspaceCentre, angles);
  if (found) guess_ = *found;
  return found;
}

std::optional<Torques> force_to_torques(const Vec& position, const Vec& force_n,
                                        double max_torque) {
  const auto j = jacobian(position);
  if (!j) return std::nullopt;
  Torques out;
  double largest = 0.0;
  for (int leg = 0; leg < 3; ++leg) {
    out.torque_nm[leg] =
        (*j)[0][leg] * force_n[0] + (*j)[1][leg] * force_n[1] + (*j)[2][leg] * force_n[2];
    largest = std::max(largest, std::abs(out.torque_nm[leg]));
  }
  if (!std::isfinite(largest)) return std::nullopt;
  if (largest > max_torque) {
    out.scale = max_torque / largest;
    for (double& torque : out.torque_nm) torque *= out.scale;
  }
  return out;
}

std::array<std::int16_t, 3> torques_to_motors(const Vec& torque_nm) {
  std::array<std::int16_t, 3> out{};
  constexpr double kLow = std::numeric_limits<std::int16_t>::min();
  constexpr double kHigh = std::numeric_limits<std::int16_t>::max();
  for (int leg = 0; leg < 3; ++leg) {
    const double motor = kMotorPerTorque * torque_nm[leg];
    // NaN gives no effort rather than an undefined conversion.
    out[leg] = std::isnan(motor)
                   ? 0
                   : static_cast<std::int16_t>(std::lround(std::clamp(motor, kLow, kHigh)));
  }
  return out;
}

}  // namespace afhub::devices::falcon
