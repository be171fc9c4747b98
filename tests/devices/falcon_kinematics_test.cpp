// The Falcon's kinematics: forward of inverse over the workspace, the Jacobian against
// finite differences, saturation that keeps the force's direction, and positions out
// of reach refused cleanly.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "afhub/devices/falcon_kinematics.hpp"

namespace afhub::devices::falcon {
namespace {

constexpr double kRadius = 0.04;  // the Falcon's workspace radius

Vec add(const Vec& a, const Vec& b, double scale = 1.0) {
  return {a[0] + scale * b[0], a[1] + scale * b[1], a[2] + scale * b[2]};
}
double distance(const Vec& a, const Vec& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

// Points of a cube of the workspace radius around the centre, `steps` per side.
std::vector<Vec> workspace_grid(int steps) {
  std::vector<Vec> points;
  for (int i = 0; i < steps; ++i) {
    for (int j = 0; j < steps; ++j) {
      for (int k = 0; k < steps; ++k) {
        const double step = 2 * kRadius / (steps - 1);
        points.push_back(
            add(kWorkspaceCentre, {-kRadius + i * step, -kRadius + j * step, -kRadius + k * step}));
      }
    }
  }
  return points;
}

TEST(FalconKinematics, EncoderCountsAndAnglesConvert) {
  EXPECT_NEAR(encoder_to_angle(0), 35.0 * M_PI / 180.0, 1e-12);
  // 1280 counts per turn of a 14.25 mm shaft on a 110 mm arc.
  EXPECT_NEAR(encoder_to_angle(1280) - encoder_to_angle(0), 2 * M_PI * 14.25 / 110.0, 1e-12);
  for (int counts : {-32768, -517, -1, 0, 1, 1000, 32767}) {
    EXPECT_NEAR(angle_to_encoder(encoder_to_angle(static_cast<std::int16_t>(counts))), counts,
                1e-9);
  }
}

TEST(FalconKinematics, TheLegsAreSymmetricAtTheCentre) {
  const auto angles = inverse(kWorkspaceCentre);
  ASSERT_TRUE(angles);
  EXPECT_NEAR((*angles)[0], (*angles)[1], 1e-12);
  EXPECT_NEAR((*angles)[1], (*angles)[2], 1e-12);
  // Pulling the grip towards the user opens every thigh.
  const auto out = inverse(add(kWorkspaceCentre, {0, 0, 0.02}));
  ASSERT_TRUE(out);
  for (int leg = 0; leg < 3; ++leg) EXPECT_GT((*out)[leg], (*angles)[leg]);
}

TEST(FalconKinematics, ForwardOfInverseOverTheWorkspace) {
  ForwardSolver warm;  // 1 kHz use: each solve starts from the previous answer
  double worst_warm = 0.0;
  double worst_cold = 0.0;
  int points = 0;
  for (const Vec& p : workspace_grid(17)) {
    const auto angles = inverse(p);
    ASSERT_TRUE(angles) << p[0] << " " << p[1] << " " << p[2];
    const auto found = warm.solve(*angles);
    ASSERT_TRUE(found) << p[0] << " " << p[1] << " " << p[2];
    worst_warm = std::max(worst_warm, distance(*found, p));
    // From the centre, as after a start or a reset: the farthest corners too.
    ForwardSolver cold;
    const auto from_centre = cold.solve(*angles);
    ASSERT_TRUE(from_centre) << p[0] << " " << p[1] << " " << p[2];
    worst_cold = std::max(worst_cold, distance(*from_centre, p));
    ++points;
  }
  EXPECT_EQ(points, 17 * 17 * 17);
  EXPECT_LT(worst_warm, 1e-6);
  EXPECT_LT(worst_cold, 1e-6);
}

TEST(FalconKinematics, JacobianMatchesFiniteDifferences) {
  constexpr double kAngleStep = 1e-6;   // rad
  constexpr double kLengthStep = 1e-7;  // m
  for (const Vec& p : workspace_grid(5)) {
    const auto j = jacobian(p);
    const auto rates = angle_jacobian(p);
    const auto angles = inverse(p);
    ASSERT_TRUE(j && rates && angles);
    // d(position)/d(theta): central differences of the forward kinematics.
    for (int leg = 0; leg < 3; ++leg) {
      LegAngles up = *angles, down = *angles;
      up[leg] += kAngleStep;
      down[leg] -= kAngleStep;
      ForwardSolver solver(p);
      const auto p_up = solver.solve(up);
      solver.reset(p);
      const auto p_down = solver.solve(down);
      ASSERT_TRUE(p_up && p_down);
      for (int axis = 0; axis < 3; ++axis) {
        const double numeric = ((*p_up)[axis] - (*p_down)[axis]) / (2 * kAngleStep);
        EXPECT_NEAR((*j)[axis][leg], numeric, 1e-5 + 1e-4 * std::abs(numeric))
            << "dp" << axis << "/dtheta" << leg;
      }
    }
    // d(theta)/d(position): central differences of the closed-form inverse.
    for (int axis = 0; axis < 3; ++axis) {
      Vec delta{};
      delta[axis] = kLengthStep;
      const auto a_up = inverse(add(p, delta));
      const auto a_down = inverse(add(p, delta, -1.0));
      ASSERT_TRUE(a_up && a_down);
      for (int leg = 0; leg < 3; ++leg) {
        const double numeric = ((*a_up)[leg] - (*a_down)[leg]) / (2 * kLengthStep);
        EXPECT_NEAR((*rates)[leg][axis], numeric, 1e-4 + 1e-5 * std::abs(numeric))
            << "dtheta" << leg << "/dp" << axis;
      }
    }
  }
}

// The force the torques render: (J^T)^-1 tau.
Vec rendered_force(const Vec& p, const Vec& torque) {
  const auto rates = angle_jacobian(p);  // (J)^-1, so (J^T)^-1 = (J^-1)^T
  Vec force{};
  for (int axis = 0; axis < 3; ++axis) {
    for (int leg = 0; leg < 3; ++leg) force[axis] += (*rates)[leg][axis] * torque[leg];
  }
  return force;
}

TEST(FalconKinematics, SaturationKeepsTheForcesDirection) {
  const Vec forces[] = {{500, 0, 0}, {0, -800, 0}, {0, 0, 1000}, {300, -400, 900}, {-1e6, 2e6, 5}};
  for (const Vec& p : workspace_grid(3)) {
    for (const Vec& force : forces) {
      const auto torques = force_to_torques(p, force);
      ASSERT_TRUE(torques);
      EXPECT_LT(torques->scale, 1.0);  // these forces are all beyond the motors
      double largest = 0.0;
      for (double t : torques->torque_nm) largest = std::max(largest, std::abs(t));
      EXPECT_NEAR(largest, kMaxTorque, 1e-9);
      const Vec rendered = rendered_force(p, torques->torque_nm);
      const double norm_f = distance(force, {});
      const double norm_r = distance(rendered, {});
      const double cosine =
          (force[0] * rendered[0] + force[1] * rendered[1] + force[2] * rendered[2]) /
          (norm_f * norm_r);
      EXPECT_NEAR(cosine, 1.0, 1e-9);
      EXPECT_NEAR(norm_r, norm_f * torques->scale, 1e-6 * norm_f);
      // The motor commands carry the same ratios, within rounding.
      const auto motors = torques_to_motors(torques->torque_nm);
      for (int leg = 0; leg < 3; ++leg) {
        EXPECT_NEAR(motors[leg], kMotorPerTorque * torques->torque_nm[leg], 0.5 + 1e-9);
      }
    }
  }
}

TEST(FalconKinematics, SmallForcesAreNotScaled) {
  const auto torques = force_to_torques(kWorkspaceCentre, {1.0, -2.0, 3.0});
  ASSERT_TRUE(torques);
  EXPECT_EQ(torques->scale, 1.0);
  const Vec rendered = rendered_force(kWorkspaceCentre, torques->torque_nm);
  EXPECT_NEAR(rendered[0], 1.0, 1e-9);
  EXPECT_NEAR(rendered[1], -2.0, 1e-9);
  EXPECT_NEAR(rendered[2], 3.0, 1e-9);
}

TEST(FalconKinematics, MotorCommandsSaturateInsteadOfWrapping) {
  // -10000 * 10 N m is -100000: a cast to int16 would wrap it to -31072's opposite sign.
  EXPECT_EQ(torques_to_motors({10.0, -10.0, 0.0}), (std::array<std::int16_t, 3>{-32768, 32767, 0}));
  EXPECT_EQ(torques_to_motors({0.1, -0.25, 1e9}),
            (std::array<std::int16_t, 3>{-1000, 2500, -32768}));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(torques_to_motors({nan, 0.0, 0.0}), (std::array<std::int16_t, 3>{0, 0, 0}));
}

TEST(FalconKinematics, OutOfReachIsRefusedCleanly) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const Vec& p : std::vector<Vec>{
           {0, 0, 0.5}, {0.3, 0, 0.11}, {0, -0.3, 0.11}, {nan, 0, 0.11}, {0, inf, 0.11}}) {
    EXPECT_FALSE(inverse(p)) << p[0] << " " << p[1] << " " << p[2];
    EXPECT_FALSE(jacobian(p));
    EXPECT_FALSE(force_to_torques(p, {1, 0, 0}));
  }
  ForwardSolver solver;
  const auto reachable = inverse(add(kWorkspaceCentre, {0.01, 0.02, -0.01}));
  ASSERT_TRUE(reachable);
  ASSERT_TRUE(solver.solve(*reachable));
  const Vec before = solver.last();
  for (const LegAngles& impossible :
       {LegAngles{3.0, -3.0, 3.0}, LegAngles{nan, 0, 0}, LegAngles{-1.5, 1.5, 1.5}}) {
    EXPECT_FALSE(solver.solve(impossible));
    EXPECT_EQ(solver.last(), before);  // the next solve starts where it was
  }
  EXPECT_TRUE(solver.solve(*reachable));
}

}  // namespace
}  // namespace afhub::devices::falcon
