// Open chains in reduced coordinates (WorldSpec::reduced_coordinates, Bullet's
// btMultiBody): which chains qualify, and that a chain so simulated behaves as the
// same chain in maximal coordinates does, against physics (a pendulum's period, a
// prismatic joint's fall onto its limit) and against the rigid world (a large swing,
// damping, a link meeting the floor), under every kind of joint command; that a link
// refuses a velocity, and that reset and a NaN put the chain back. The real KUKA's PID
// targets: simulation_test.cpp. No hub.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/simulation.hpp"
#include "chains.hpp"
#include "model_files.hpp"

namespace afhub::physics::reduced_test {  // a unity build joins the tests' files
namespace {

constexpr double kGravity = 9.81;

Model load(const std::string& text, bool reduced = true) {
  testing::ModelFolder folder;
  Model model = load_adf_files({folder.write("model.yaml", text)});
  model.world.reduced_coordinates = reduced;
  return model;
}

// A static base and a 1 kg box link of `length` on joint `j` (about y, or along x
// when prismatic), its pivot at the base's origin; the link lies along x from it.
std::string one_link(const std::string& type, double length = 0.5,
                     const std::string& extra_joint = "", const std::string& extra_body = "",
                     const std::string& header = "") {
  const std::string half = std::to_string(length / 2);
  return header +
         "bodies: [BODY base, BODY link]\njoints: [JOINT j]\n"
         "BODY base:\n  name: base\n  mass: 0\n"
         "BODY link:\n  name: link\n  mass: 1\n  shape: box\n  geometry: {x: " +
         std::to_string(length) + ", y: 0.02, z: 0.02}\n  location: {position: {x: " + half +
         ", y: 0, z: 0}}\n" + extra_body +
         "JOINT j:\n  name: j\n  parent: BODY base\n  child: BODY link\n"
         "  parent pivot: {x: 0, y: 0, z: 0}\n  parent axis: {x: " +
         (type == "prismatic" ? "1, y: 0" : "0, y: 1") + ", z: 0}\n  child pivot: {x: -" + half +
         ", y: 0, z: 0}\n  child axis: {x: " + (type == "prismatic" ? "1, y: 0" : "0, y: 1") +
         ", z: 0}\n  type: " + type + "\n" + extra_joint;
}

void step_for(Simulation& sim, double seconds) {
  const auto steps = std::lround(seconds / sim.dt_s());
  for (long i = 0; i < steps; ++i) sim.step();
  ASSERT_TRUE(sim.all_finite());
}

TEST(ReducedCoordinates, OnlyOpenChainsOnAStaticBodyQualify) {
  const Model arm = load_adf_files({AFHUB_EXAMPLE_MODELS "/arm7.yaml"});
  const std::vector<ChainPlan> chains = plan_chains(arm);
  ASSERT_EQ(chains.size(), 1u);
  EXPECT_EQ(arm.bodies[chains[0].base].name, "mount");
  EXPECT_EQ(chains[0].joints.size(), 8u);  // the base and seven links
  for (std::size_t l = 0; l < chains[0].joints.size(); ++l)
    EXPECT_LT(chains[0].parent[l], static_cast<int>(l)) << "parents before children";
  // Closed loops, and a gripper whose actuators hold what they touch, stay rigid.
  EXPECT_TRUE(plan_chains(load_adf_files({AFHUB_EXAMPLE_MODELS "/rcm.yaml"})).empty());
  EXPECT_TRUE(plan_chains(load_adf_files({AFHUB_EXAMPLE_MODELS "/gripper.yaml"})).empty());
  // A joint with its own error settings, and a spring, stay rigid too.
  EXPECT_EQ(plan_chains(load(one_link("revolute"))).size(), 1u);
  EXPECT_TRUE(plan_chains(load(one_link("revolute", 0.5, "  joint erp: 0.3\n"))).empty());
  EXPECT_TRUE(plan_chains(load(one_link("torsion spring"))).empty());

  Model model = arm;
  model.world.reduced_coordinates = true;
  EXPECT_EQ(Simulation(model, 0.001).links_in_reduced_coordinates(), 8u);
  model.world.reduced_coordinates = false;
  EXPECT_EQ(Simulation(model, 0.001).links_in_reduced_coordinates(), 0u);
}

// A small swing's period against the compound pendulum's, and a swing released from
// horizontal against the same link in maximal coordinates, step by step.
TEST(ReducedCoordinates, APendulumSwingsAsPhysicsAndTheRigidWorldSay) {
  const std::string text = one_link("continuous", 0.5, "", "  damping: {linear: 0, angular: 0}\n");
  // Released horizontal: both worlds, 2 s.
  const Model reduced_model = load(text, true), rigid_model = load(text, false);
  Simulation reduced(reduced_model, 0.001), rigid(rigid_model, 0.001);
  ASSERT_EQ(reduced.links_in_reduced_coordinates(), 1u);
  double largest = 0.0, lowest = 0.0;
  for (int i = 0; i < 2000; ++i) {
    reduced.step();
    rigid.step();
    largest = std::max(largest, std::abs(reduced.joint_position(0) - rigid.joint_position(0)));
    lowest = std::max(lowest, reduced.joint_position(0));
  }
  EXPECT_LT(largest, 0.02) << "rad apart at most";
  // Undamped, it swings down through vertical (pi/2) and on to the other side (pi).
  EXPECT_GT(lowest, 0.95 * M_PI);
  // Its period: a uniform rod about its end, 2 pi sqrt(2 L / 3 g) times the large-swing
  // factor for a release at 90 degrees (1.18034).
  const double period = 2 * M_PI * std::sqrt(2 * 0.5 / (3 * kGravity)) * 1.18034;
  Simulation timed(reduced_model, 0.001);
  double previous = timed.joint_position(0), last_turn = -1;
  bool rising = true;
  int turns = 0;
  double first_turn = -1;
  while (timed.time_s() < 5.0) {
    timed.step();
    const double now = timed.joint_position(0);
    if (rising && now < previous) {  // the far end of a swing
      if (first_turn < 0) first_turn = timed.time_s();
      last_turn = timed.time_s();
      ++turns;
    }
    rising = now >= previous;
    previous = now;
  }
  ASSERT_GE(turns, 3);
  EXPECT_NEAR((last_turn - first_turn) / (turns - 1), period, 0.01 * period);
}

// Effort, velocity and position commands move a revolute and a prismatic link the way
// its position counts, and a position command is reached (gravity off).
TEST(ReducedCoordinates, JointCommandsMoveTheLink) {
  for (const std::string type : {"revolute", "prismatic"}) {
    const Model model =
        load(one_link(type, 0.2, "  controller: {P: 20, I: 0, D: 2}\n  max motor impulse: 1\n", "",
                      "gravity: {x: 0, y: 0, z: 0}\n"));
    for (JointMode kind : {JointMode::kEffort, JointMode::kVelocity, JointMode::kPosition}) {
      Simulation sim(model, 0.001);
      ASSERT_EQ(sim.links_in_reduced_coordinates(), 1u);
      BodyInput command{};
      command.joint_count = 1;
      command.joint_modes[0] = kind;
      command.joint_values[0] = 0.3;
      ASSERT_EQ(sim.input_problem(0, command), nullptr);
      sim.set_input(0, command);
      step_for(sim, kind == JointMode::kPosition ? 6.0 : 0.5);
      EXPECT_GT(sim.joint_position(0), 0.02) << type << " command " << static_cast<int>(kind);
      if (kind == JointMode::kPosition) {
        EXPECT_NEAR(sim.joint_position(0), 0.3, 0.01) << type;
      }
      if (kind == JointMode::kVelocity) {
        EXPECT_NEAR(sim.joint_velocity(0), 0.3, 0.01) << type;
      }
      EXPECT_EQ(sim.joint_pivot_gap_m(0), 0.0) << "a coordinate cannot open";
    }
  }
}

// A prismatic link falling along its axis stops on its limit; a revolute link swinging
// down stops on its own, at the speed gravity gives it.
TEST(ReducedCoordinates, LimitsHold) {
  const std::string limits = "  joint limits: {low: -0.05, high: 0.05}\n";
  const Model slide =
      load(one_link("prismatic", 0.2, limits, "", "gravity: {x: -9.81, y: 0, z: 0}\n"));
  Simulation falling(slide, 0.001);
  step_for(falling, 1.0);
  EXPECT_NEAR(falling.joint_position(0), -0.05, 0.001);
  const Model swing = load(one_link("revolute", 0.5, "  joint limits: {low: -0.5, high: 0.5}\n"));
  Simulation swinging(swing, 0.001);
  double highest = 0;
  for (int i = 0; i < 2000; ++i) {
    swinging.step();
    highest = std::max(highest, swinging.joint_position(0));
  }
  EXPECT_LT(highest, 0.51);
  EXPECT_NEAR(swinging.joint_position(0), 0.5, 0.01);
}

// A link swinging down onto the floor rests on it, as in maximal coordinates.
TEST(ReducedCoordinates, ALinkRestsOnTheFloor) {
  std::string text = one_link("revolute", 0.5);
  text.replace(text.find("bodies: [BODY base, BODY link]"), 30,
               "bodies: [BODY base, BODY link, BODY floor]");
  text +=
      "BODY floor:\n  name: floor\n  mass: 0\n  shape: box\n  geometry: {x: 2, y: 2, z: 0.1}\n"
      "  location: {position: {x: 0, y: 0, z: -0.35}}\n";
  double rest[2] = {0, 0};
  for (bool reduced : {true, false}) {
    const Model model = load(text, reduced);
    Simulation sim(model, 0.001);
    step_for(sim, 3.0);
    rest[reduced ? 0 : 1] = sim.joint_position(0);
    // The floor's top is 0.3 m below the pivot: the link's end stops there.
    const double end_z = -0.5 * std::sin(sim.joint_position(0));
    EXPECT_NEAR(end_z, -0.3, 0.02) << (reduced ? "reduced" : "rigid");
  }
  EXPECT_NEAR(rest[0], rest[1], 0.02);
}

// AMBF's damping (btRigidBody: v scaled by (1 - damping)^dt a step) and a body's own
// gravity over the world's hold as in maximal coordinates.
TEST(ReducedCoordinates, DampingAndABodysOwnGravityActAsOnARigidBody) {
  const std::string damped =
      one_link("continuous", 0.5, "", "  damping: {linear: 0.5, angular: 0.9}\n");
  const Model reduced_model = load(damped, true), rigid_model = load(damped, false);
  Simulation reduced(reduced_model, 0.001), rigid(rigid_model, 0.001);
  step_for(reduced, 0.4);
  step_for(rigid, 0.4);
  EXPECT_NEAR(reduced.joint_velocity(0), rigid.joint_velocity(0),
              0.02 * std::abs(rigid.joint_velocity(0)));
  EXPECT_NEAR(reduced.joint_position(0), rigid.joint_position(0), 0.01);
  // The file says no gravity for its bodies: the horizontal link stays where it is.
  const Model weightless = load(one_link("continuous", 0.5, "", "  gravity: {x: 0, y: 0, z: 0}\n"));
  Simulation still(weightless, 0.001);
  step_for(still, 1.0);
  EXPECT_NEAR(still.joint_position(0), 0.0, 1e-6);
}

// A link is pushed, never given a velocity: a twist, or a pose through a PID whose
// output is a velocity, is refused naming why; a wrench moves it.
TEST(ReducedCoordinates, ALinkRefusesAVelocityAndTakesAWrench) {
  const Model model = load(one_link("continuous", 0.5, "", "", "gravity: {x: 0, y: 0, z: 0}\n"));
  Simulation sim(model, 0.001);
  BodyInput twist{};
  twist.cartesian = CartesianMode::kVelocity;
  twist.twist.linear_mps = {0, 0, 0.1};
  const char* problem = sim.input_problem(1, twist);
  ASSERT_NE(problem, nullptr);
  EXPECT_NE(std::string(problem).find("reduced coordinates"), std::string::npos) << problem;
  BodyInput pose{};
  pose.cartesian = CartesianMode::kPosition;
  pose.target_pose.orientation.w = 1;
  EXPECT_NE(sim.input_problem(1, pose), nullptr) << "its PID outputs a velocity";
  BodyInput push{};
  push.wrench.force_n = {0, 0, -1};  // at the centre, 0.25 m out: 0.25 N m about y
  ASSERT_EQ(sim.input_problem(1, push), nullptr);
  sim.set_input(1, push);
  step_for(sim, 0.2);
  // theta = tau t^2 / 2 I, I = m L^2 / 3.
  EXPECT_NEAR(sim.joint_position(0), 0.25 * 0.04 / 2 / (0.25 / 3), 0.01);
}

// Reset, and a step that made the chain NaN (a NaN force, past the checks), put the
// chain back: at its start, and where it last was finite, at rest.
TEST(ReducedCoordinates, ResetAndANanPutTheChainBack) {
  const Model model = load(one_link("continuous"));
  Simulation sim(model, 0.001);
  step_for(sim, 0.3);
  const double before = sim.joint_position(0);
  EXPECT_GT(before, 0.1);
  BodyInput absurd{};
  absurd.wrench.force_n = {0, 0, std::nan("")};
  sim.set_input(1, absurd);  // unchecked: input_problem would refuse it
  sim.step();
  EXPECT_TRUE(sim.all_finite());
  EXPECT_EQ(sim.nan_recoveries().count, 1u);
  EXPECT_EQ(sim.nan_recoveries().last.body, 1u);
  EXPECT_EQ(sim.joint_position(0), before);
  EXPECT_EQ(sim.joint_velocity(0), 0.0);
  sim.step();
  EXPECT_EQ(sim.nan_recoveries().count, 1u) << "its command was released";
  sim.reset();
  EXPECT_NEAR(sim.joint_position(0), 0.0, 1e-12);
  EXPECT_NEAR(sim.body_pose(1).position_m.x, 0.25, 1e-9);
  step_for(sim, 0.3);
  EXPECT_NEAR(sim.joint_position(0), before, 1e-9) << "from the start, as the first time";
}

}  // namespace
}  // namespace afhub::physics::reduced_test
