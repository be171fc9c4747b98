// subtree_contact_wrench: the contact wrenches of a multibody's bodies summed at its
// root, each torque moved to the root's origin.
#include "afhub/teleop/subtree_contact.hpp"

#include <gtest/gtest.h>

#include <array>

#include "heap_counter.hpp"

namespace afhub::teleop {
namespace {

BodyState body_at(const Vec3& origin, const Vec3& force, const Vec3& torque = {}) {
  BodyState state;
  state.pose.position_m = origin;
  state.contact_wrench = {force, torque};
  return state;
}

void expect_vec(const Vec3& got, const Vec3& want) {
  EXPECT_NEAR(got.x, want.x, 1e-12);
  EXPECT_NEAR(got.y, want.y, 1e-12);
  EXPECT_NEAR(got.z, want.z, 1e-12);
}

TEST(SubtreeContact, TheRootAloneGivesItsOwnContactWrench) {
  const BodyState palm = body_at({0.6, 0.8, 0.6}, {1, 2, 3}, {0.1, 0.2, 0.3});
  const std::array<const BodyState*, 1> bodies{&palm};
  const Wrench sum = subtree_contact_wrench(palm.pose.position_m, bodies);
  expect_vec(sum.force_n, {1, 2, 3});
  expect_vec(sum.torque_nm, {0.1, 0.2, 0.3});
}

TEST(SubtreeContact, NothingTouchingGivesZero) {
  const BodyState palm = body_at({0.6, 0.8, 0.6}, {});
  const BodyState finger = body_at({0.655, 0.836, 0.6}, {});
  const std::array<const BodyState*, 3> bodies{&palm, &finger, nullptr};
  const Wrench sum = subtree_contact_wrench(palm.pose.position_m, bodies);
  expect_vec(sum.force_n, {});
  expect_vec(sum.torque_nm, {});
}

// A finger 10 cm ahead of the palm pushed up 5 N (its own torque 0.01 about z): the
// root gets the 5 N and, about its origin, the finger's torque plus r x f.
TEST(SubtreeContact, AFingersContactIsFeltAtTheRootWithItsLever) {
  const BodyState palm = body_at({1, 2, 3}, {});
  const BodyState finger = body_at({1.1, 2, 3}, {0, 0, 5}, {0, 0, 0.01});
  const std::array<const BodyState*, 2> bodies{&palm, &finger};
  const Wrench sum = subtree_contact_wrench(palm.pose.position_m, bodies);
  expect_vec(sum.force_n, {0, 0, 5});
  expect_vec(sum.torque_nm, {0, -0.5, 0.01});  // (0.1, 0, 0) x (0, 0, 5) = (0, -0.5, 0)
}

TEST(SubtreeContact, EveryBodysContactAddsUpAndMissingStatesAddNothing) {
  const BodyState palm = body_at({0, 0, 0}, {0, 0, 1});
  const BodyState left = body_at({0, 1, 0}, {0, -2, 0});
  const BodyState right = body_at({0, -1, 0}, {3, 0, 0});
  const std::array<const BodyState*, 4> bodies{&palm, nullptr, &left, &right};
  const Wrench sum = subtree_contact_wrench(palm.pose.position_m, bodies);
  expect_vec(sum.force_n, {3, -2, 1});
  // left: (0,1,0) x (0,-2,0) = 0; right: (0,-1,0) x (3,0,0) = (0, 0, 3)
  expect_vec(sum.torque_nm, {0, 0, 3});
}

// A contact between two of the multibody's bodies (equal and opposite forces at one
// point, each torque about its own body's origin) pushes the whole not at all.
TEST(SubtreeContact, ContactsBetweenItsOwnBodiesCancel) {
  const Vec3 point{0.3, -0.2, 0.5};
  const Vec3 f{1.5, -2.0, 4.0};
  const Vec3 p_palm{0.1, 0.1, 0.1}, p_finger{0.4, 0.2, 0.3};
  const auto moment = [](const Vec3& r, const Vec3& v) {
    return Vec3{r.y * v.z - r.z * v.y, r.z * v.x - r.x * v.z, r.x * v.y - r.y * v.x};
  };
  const auto minus = [](const Vec3& a, const Vec3& b) {
    return Vec3{a.x - b.x, a.y - b.y, a.z - b.z};
  };
  const Vec3 neg{-f.x, -f.y, -f.z};
  const BodyState palm = body_at(p_palm, f, moment(minus(point, p_palm), f));
  const BodyState finger = body_at(p_finger, neg, moment(minus(point, p_finger), neg));
  const std::array<const BodyState*, 2> bodies{&palm, &finger};
  const Wrench sum = subtree_contact_wrench(p_palm, bodies);
  expect_vec(sum.force_n, {});
  expect_vec(sum.torque_nm, {});
}

TEST(SubtreeContact, AllocatesNothing) {
  const BodyState palm = body_at({0, 0, 0}, {0, 0, 1});
  const BodyState finger = body_at({0.1, 0, 0}, {0, 0, 1});
  const std::array<const BodyState*, 2> bodies{&palm, &finger};
  const long before = test::heap_allocations();
  double z = 0.0;
  for (int i = 0; i < 100; ++i) z += subtree_contact_wrench({}, bodies).force_n.z;
  EXPECT_EQ(test::heap_allocations() - before, 0);
  EXPECT_EQ(z, 200.0);
}

}  // namespace
}  // namespace afhub::teleop
