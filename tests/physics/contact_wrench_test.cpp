// Each body's contact wrench (BodyReading::contact_wrench), against statics: a box
// resting on the floor carries its weight, a falling one touches nothing, a box held
// by friction or pushed into a wall is pushed back as hard as it is pushed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/simulation.hpp"
#include "model_files.hpp"

namespace afhub::physics {
namespace {

constexpr double kWorldGravity = 9.81;
constexpr double kMass = 2.0;
constexpr double kWeight = kMass * kWorldGravity;

// The floor (static, its top the plane z = 0), a 10 cm box of 2 kg resting on it at
// the origin, a box falling from 5 m, and a static wall whose face is at x = 0.25.
std::string scene() {
  const std::string box =
      "  mass: 2.0\n  shape: box\n  geometry: {x: 0.1, y: 0.1, z: 0.1}\n"
      "  friction: {static: 0.5, rolling: 0}\n  restitution: 0\n"
      "  damping: {linear: 0, angular: 0}\n";
  return "bodies: [BODY floor, BODY block, BODY faller, BODY wall]\n"
         "BODY floor:\n  name: floor\n  mass: 0\n  shape: box\n"
         "  geometry: {x: 4, y: 4, z: 0.1}\n  friction: {static: 0.5, rolling: 0}\n"
         "  location: {position: {x: 0, y: 0, z: -0.05}}\n"
         "BODY block:\n  name: block\n" +
         box +
         "  location: {position: {x: 0, y: 0, z: 0.05}}\n"
         "BODY faller:\n  name: faller\n" +
         box +
         "  location: {position: {x: 1, y: 1, z: 5}}\n"
         "BODY wall:\n  name: wall\n  mass: 0\n  shape: box\n  geometry: {x: 0.1, y: 1, z: 1}\n"
         "  friction: {static: 0.5, rolling: 0}\n"
         "  location: {position: {x: 0.3, y: 0, z: 0.5}}\n";
}

enum Body { kFloor = 0, kBlock = 1, kFaller = 2, kWall = 3 };

class ContactWrench : public ::testing::Test {
 protected:
  ContactWrench()
      : model_(load_adf_files({folder_.write("contacts.yaml", scene())})), sim_(model_, 0.001) {}

  // Steps `steps` times with the block pushed by `push` (world frame, at its centre of
  // mass); returns the block's mean contact wrench over the last `mean_of` steps.
  Wrench push_block(const Vec3& push, int steps, int mean_of) {
    input_.wrench.force_n = push;
    EXPECT_EQ(sim_.input_problem(kBlock, input_), nullptr);
    sim_.set_input(kBlock, input_);
    Wrench sum;
    for (int i = 0; i < steps; ++i) {
      sim_.step();
      if (i < steps - mean_of) continue;
      sim_.read_body(kBlock, reading_);
      add(sum.force_n, reading_.contact_wrench.force_n);
      add(sum.torque_nm, reading_.contact_wrench.torque_nm);
    }
    const double n = mean_of;
    return {{sum.force_n.x / n, sum.force_n.y / n, sum.force_n.z / n},
            {sum.torque_nm.x / n, sum.torque_nm.y / n, sum.torque_nm.z / n}};
  }

  static void add(Vec3& to, const Vec3& v) { to = {to.x + v.x, to.y + v.y, to.z + v.z}; }

  testing::ModelFolder folder_;
  Model model_;
  Simulation sim_;
  BodyInput input_{};
  BodyReading reading_{};
};

TEST_F(ContactWrench, ABoxRestingOnTheFloorCarriesItsWeightAndAFallingOneNothing) {
  // The faller is in the air for its first second (it falls 4.9 m of its 5): no
  // contact at any step.
  double faller_most = 0.0;
  std::uint32_t faller_contacts = 0;
  int steps_touching = 0;
  Wrench resting;
  constexpr int kSteps = 1000, kMeanOf = 500;
  for (int i = 0; i < kSteps; ++i) {
    sim_.step();
    sim_.read_body(kFaller, reading_);
    const Vec3& f = reading_.contact_wrench.force_n;
    faller_most = std::max(faller_most, std::hypot(f.x, f.y, f.z));
    faller_contacts = std::max(faller_contacts, reading_.contact_count);
    if (i < kSteps - kMeanOf) continue;
    sim_.read_body(kBlock, reading_);
    add(resting.force_n, reading_.contact_wrench.force_n);
    add(resting.torque_nm, reading_.contact_wrench.torque_nm);
    if (reading_.contact_count > 0) ++steps_touching;
  }
  const Vec3 f{resting.force_n.x / kMeanOf, resting.force_n.y / kMeanOf,
               resting.force_n.z / kMeanOf};
  const Vec3 t{resting.torque_nm.x / kMeanOf, resting.torque_nm.y / kMeanOf,
               resting.torque_nm.z / kMeanOf};
  std::printf(
      "resting box: contact force (%.4f, %.4f, %.4f) N, m g = %.4f N (%+.3f%%), torque about "
      "its centre (%.2e, %.2e, %.2e) N m, %u points; falling box: largest %.3g N\n",
      f.x, f.y, f.z, kWeight, 100.0 * (f.z - kWeight) / kWeight, t.x, t.y, t.z,
      reading_.contact_count, faller_most);
  EXPECT_EQ(faller_most, 0.0);
  EXPECT_EQ(faller_contacts, 0u);
  EXPECT_EQ(steps_touching, kMeanOf);
  EXPECT_NEAR(f.z, kWeight, 0.02 * kWeight);  // upward, m g
  EXPECT_NEAR(f.x, 0.0, 0.01 * kWeight);
  EXPECT_NEAR(f.y, 0.0, 0.01 * kWeight);
  // Centred support: no moment about the box's centre (its mesh frame origin).
  EXPECT_LT(std::hypot(t.x, t.y, t.z), 0.01 * kWeight * 0.05);
  // The floor feels the same contacts from the other side: the box's weight, down.
  sim_.read_body(kFloor, reading_);
  EXPECT_NEAR(reading_.contact_wrench.force_n.z, -kWeight, 0.05 * kWeight);
  EXPECT_GT(reading_.contact_count, 0u);
}

TEST_F(ContactWrench, FrictionHoldsABoxPushedLessThanItsGrip) {
  // 3 N sideways, under the 4.9 N friction can give (Bullet multiplies the two
  // bodies' friction: 0.5 * 0.5 * m g): the box stays, the floor pushes back 3 N.
  constexpr double kPush = 3.0;
  const double x0 = sim_.body_pose(kBlock).position_m.x;
  const Wrench w = push_block({kPush, 0.0, 0.0}, 1000, 500);
  std::printf("box pushed %.0f N along x on the floor: contact force (%.4f, %.4f, %.4f) N\n", kPush,
              w.force_n.x, w.force_n.y, w.force_n.z);
  EXPECT_LT(std::abs(sim_.body_pose(kBlock).position_m.x - x0), 0.001) << "the box slid";
  EXPECT_NEAR(w.force_n.x, -kPush, 0.03 * kPush);
  EXPECT_NEAR(w.force_n.y, 0.0, 0.01 * kPush);
  EXPECT_NEAR(w.force_n.z, kWeight, 0.02 * kWeight);
}

TEST_F(ContactWrench, ABoxPushedIntoAWallIsPushedBack) {
  // 30 N along x slides the box 20 cm into the wall, where it stays pressed: the
  // contacts (the wall's, the floor's) cancel the push and the weight.
  constexpr double kPush = 30.0;
  const Wrench w = push_block({kPush, 0.0, 0.0}, 2000, 500);
  sim_.read_body(kWall, reading_);
  const Vec3 on_wall = reading_.contact_wrench.force_n;
  std::printf(
      "box pushed %.0f N into the wall: contact force on the box (%.4f, %.4f, %.4f) N, on the "
      "wall (%.4f, %.4f, %.4f) N\n",
      kPush, w.force_n.x, w.force_n.y, w.force_n.z, on_wall.x, on_wall.y, on_wall.z);
  EXPECT_NEAR(sim_.body_pose(kBlock).position_m.x, 0.2, 0.005) << "the box is not at the wall";
  EXPECT_NEAR(w.force_n.x, -kPush, 0.03 * kPush);
  EXPECT_NEAR(w.force_n.y, 0.0, 0.01 * kPush);
  EXPECT_NEAR(w.force_n.z, kWeight, 0.03 * kWeight);
  EXPECT_GT(on_wall.x, 0.5 * kPush) << "the wall is not pushed";
}

}  // namespace
}  // namespace afhub::physics
