// Joint gains from outside the model files (`afhub run --default-gains`, `--gains`):
// the loader says which joints' files give a `controller`; the default reaches only
// the others; a named joint, or every joint below a named body, takes its gains over
// the file's; bad gains and unknown or ambiguous names are errors naming the option.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/gain_overrides.hpp"
#include "afhub/physics/simulation.hpp"
#include "afhub/shm_layout/error.hpp"
#include "model_files.hpp"
#include "text_contains.hpp"

namespace afhub::physics {
namespace {

// A static base, a link on `shoulder` (whose file gives gains) and a tip on `elbow`
// (whose file gives none), in namespace `name_space`.
std::string two_joints(const std::string& name_space) {
  std::string body_block;
  for (const char* body : {"base", "upper", "tip"})
    body_block += "BODY " + std::string(body) + ":\n  name: " + body +
                  "\n  mass: " + (std::string(body) == "base" ? "0" : "1") +
                  "\n  shape: box\n  geometry: {x: 0.2, y: 0.02, z: 0.02}\n";
  auto joint = [](const std::string& name, const std::string& parent, const std::string& child,
                  const std::string& extra) {
    return "JOINT " + name + ":\n  name: " + name + "\n  parent: BODY " + parent +
           "\n  child: BODY " + child +
           "\n  parent pivot: {x: 0, y: 0, z: 0}\n  child pivot: {x: 0, y: 0, z: 0}\n"
           "  parent axis: {x: 0, y: 0, z: 1}\n  child axis: {x: 0, y: 0, z: 1}\n"
           "  type: revolute\n" +
           extra;
  };
  return "bodies: [BODY base, BODY upper, BODY tip]\njoints: [JOINT shoulder, JOINT elbow]\n"
         "namespace: " +
         name_space + "\ngravity: {x: 0, y: 0, z: 0}\n" + body_block +
         joint("shoulder", "base", "upper", "  controller: {P: 50, I: 0, D: 2}\n") +
         joint("elbow", "upper", "tip", "");
}

std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

using afhub::test::contains;

TEST(GainOverrides, TheLoaderSaysWhichFilesGiveGains) {
  testing::ModelFolder folder;
  const Model model = load_adf_files({folder.write("arm.yaml", two_joints("/arm/"))});
  ASSERT_EQ(model.joints.size(), 2u);
  EXPECT_EQ(model.joints[0].gains_from, GainSource::kFile);
  EXPECT_EQ(model.joints[0].controller.p, 50.0);
  EXPECT_EQ(model.joints[1].gains_from, GainSource::kAmbfDefault);
  EXPECT_EQ(model.joints[1].controller.p, 10.0);  // AMBF's default P 10, I 0, D 1
  EXPECT_EQ(model.joints[1].controller.d, 1.0);
}

TEST(GainOverrides, DefaultGainsReachOnlyTheJointsWithoutTheirOwn) {
  testing::ModelFolder folder;
  Model model = load_adf_files({folder.write("arm.yaml", two_joints("/arm/"))});
  EXPECT_EQ(set_default_gains(model, {300.0, 1.0, 4.0}), 1u);
  EXPECT_EQ(model.joints[0].controller.p, 50.0) << "the file's gains stay";
  EXPECT_EQ(model.joints[1].controller.p, 300.0);
  EXPECT_EQ(model.joints[1].controller.i, 1.0);
  EXPECT_EQ(model.joints[1].controller.d, 4.0);
  EXPECT_EQ(model.joints[1].gains_from, GainSource::kCommandLine);
  // The simulation uses them (within the stability cap, which they are).
  Simulation sim(model, 0.001);
  EXPECT_EQ(sim.joint_gains(1).p, 300.0);
  EXPECT_EQ(sim.joint_gains(0).p, 50.0);
}

TEST(GainOverrides, NamedJointsAndBodiesTakeGainsOverTheFiles) {
  testing::ModelFolder folder;
  Model model = load_adf_files({folder.write("arm.yaml", two_joints("/arm/"))});
  set_gains(model, "arm/shoulder", {70.0, 0.0, 3.0}, "--gains");  // a joint, its full name
  EXPECT_EQ(model.joints[0].controller.p, 70.0);
  EXPECT_EQ(model.joints[1].controller.p, 10.0);
  set_gains(model, "elbow", {80.0, 0.0, 3.0}, "--gains");  // a joint, its last part
  EXPECT_EQ(model.joints[1].controller.p, 80.0);
  set_gains(model, "upper", {90.0, 0.0, 3.0}, "--gains");  // a body: the joints below it
  EXPECT_EQ(model.joints[0].controller.p, 70.0);
  EXPECT_EQ(model.joints[1].controller.p, 90.0);
  set_gains(model, "/arm/base/", {95.0, 0.0, 3.0}, "--gains");  // the root: every joint
  EXPECT_EQ(model.joints[0].controller.p, 95.0);
  EXPECT_EQ(model.joints[1].controller.p, 95.0);
  EXPECT_EQ(model.joints[0].gains_from, GainSource::kCommandLine);
}

TEST(GainOverrides, UnknownAndAmbiguousNamesAreErrorsWithTheCandidates) {
  testing::ModelFolder folder;
  Model model = load_adf_files({folder.write("one.yaml", two_joints("/one/")),
                                folder.write("two.yaml", two_joints("/two/"))});
  const std::string unknown = error_of([&] {
    set_gains(model, "wrist", {1.0, 0.0, 0.0}, "--gains");
  });
  EXPECT_TRUE(contains(unknown, "--gains: no joint or body is named 'wrist'")) << unknown;
  EXPECT_TRUE(contains(unknown, "one/shoulder")) << unknown;
  const std::string ambiguous = error_of([&] {
    set_gains(model, "elbow", {1.0, 0.0, 0.0}, "--gains");
  });
  EXPECT_TRUE(contains(ambiguous, "'elbow' is ambiguous")) << ambiguous;
  EXPECT_TRUE(contains(ambiguous, "joint one/elbow")) << ambiguous;
  EXPECT_TRUE(contains(ambiguous, "joint two/elbow")) << ambiguous;
  set_gains(model, "two/elbow", {1.0, 0.0, 0.0}, "--gains");
  EXPECT_EQ(model.joints[3].channel, "two/elbow");
  EXPECT_EQ(model.joints[3].controller.p, 1.0);
  EXPECT_EQ(model.joints[1].controller.p, 10.0);
  const std::string leaf = error_of([&] {
    set_gains(model, "one/tip", {1.0, 0.0, 0.0}, "--gains");
  });
  EXPECT_TRUE(contains(leaf, "body one/tip has no joints below it")) << leaf;
}

TEST(GainOverrides, BadGainsAreErrorsNamingTheOption) {
  testing::ModelFolder folder;
  Model model = load_adf_files({folder.write("arm.yaml", two_joints("/arm/"))});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const Pid& bad : {Pid{-1.0, 0.0, 1.0}, Pid{1.0, nan, 1.0}, Pid{1.0, 0.0, inf}}) {
    const std::string by_default = error_of([&] { set_default_gains(model, bad); });
    EXPECT_TRUE(contains(by_default,
                         "--default-gains: gains P, I and D must be finite and not "
                         "negative"))
        << by_default;
    const std::string named = error_of([&] { set_gains(model, "elbow", bad, "--gains"); });
    EXPECT_TRUE(contains(named, "--gains: gains P, I and D")) << named;
  }
  EXPECT_EQ(model.joints[1].controller.p, 10.0) << "nothing was set";
}

// What the run's report measures tracking against: the position a joint is commanded to.
TEST(GainOverrides, TheSimulationSaysAJointsPositionTarget) {
  testing::ModelFolder folder;
  const Model model = load_adf_files({folder.write("arm.yaml", two_joints("/arm/"))});
  Simulation sim(model, 0.001);
  double target = 0.0;
  EXPECT_FALSE(sim.joint_position_target(1, target));
  BodyInput input{};
  input.joint_count = 2;
  input.joint_modes[0] = JointMode::kEffort;
  input.joint_modes[1] = JointMode::kPosition;
  input.joint_values[1] = 0.25;
  ASSERT_EQ(sim.input_problem(0, input), nullptr);
  sim.set_input(0, input);
  EXPECT_FALSE(sim.joint_position_target(0, target)) << "an effort command has no target";
  ASSERT_TRUE(sim.joint_position_target(1, target));
  EXPECT_EQ(target, 0.25);
}

}  // namespace
}  // namespace afhub::physics
