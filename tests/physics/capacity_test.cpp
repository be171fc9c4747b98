// Models as large as real AMBF scenes run under the hub: a chain of 200 links whose
// root reports (and takes commands for) all 200 joints below it, and a scene of 400
// active bodies, every one in the catalog and publishing.
#include <gtest/gtest.h>

#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub_process.hpp"
#include "model_files.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

// One active root (static) with `links` passive links below it in a straight chain,
// each joint about Z with a velocity-output PID; no gravity.
std::string chain_model(int links) {
  std::string text = "adf version: '1.0'\nnamespace: /capacity/chain/\n";
  text += "gravity: {x: 0.0, y: 0.0, z: 0.0}\nignore inter-collision: true\nbodies: [BODY base";
  for (int i = 1; i <= links; ++i) text += ", BODY link" + std::to_string(i);
  text += "]\njoints: [";
  for (int i = 1; i <= links; ++i)
    text += (i > 1 ? ", " : "") + std::string("JOINT j") + std::to_string(i);
  text += "]\nBODY base:\n  name: base\n  mass: 0.0\n  shape: sphere\n  geometry: {radius: 0.02}\n";
  for (int i = 1; i <= links; ++i) {
    text += "BODY link" + std::to_string(i) + ":\n  name: link" + std::to_string(i) +
            "\n  mass: 0.1\n  inertia: {ix: 0.0001, iy: 0.0001, iz: 0.0001}\n  passive: true\n"
            "  shape: sphere\n  geometry: {radius: 0.02}\n  location:\n    position: {x: 0.0, "
            "y: 0.0, z: " +
            std::to_string(0.05 * i) + "}\n";
    const std::string parent = i == 1 ? "base" : "link" + std::to_string(i - 1);
    text += "JOINT j" + std::to_string(i) + ":\n  name: j" + std::to_string(i) +
            "\n  parent: BODY " + parent + "\n  child: BODY link" + std::to_string(i) +
            "\n  type: revolute\n  parent pivot: {x: 0.0, y: 0.0, z: 0.025}\n"
            "  parent axis: {x: 0.0, y: 0.0, z: 1.0}\n  child pivot: {x: 0.0, y: 0.0, z: -0.025}\n"
            "  child axis: {x: 0.0, y: 0.0, z: 1.0}\n  controller: {P: 10.0, I: 0.0, D: 0.0}\n"
            "  controller output type: VELOCITY\n  max motor impulse: 0.01\n";
  }
  return text;
}

// `count` active free spheres on a grid, 0.5 m apart; no gravity.
std::string scene_model(int count) {
  std::string text = "adf version: '1.0'\nnamespace: /capacity/scene/\n";
  text += "gravity: {x: 0.0, y: 0.0, z: 0.0}\nbodies: [";
  for (int i = 0; i < count; ++i)
    text += (i ? ", " : "") + std::string("BODY b") + std::to_string(i);
  text += "]\n";
  for (int i = 0; i < count; ++i)
    text += "BODY b" + std::to_string(i) + ":\n  name: b" + std::to_string(i) +
            "\n  mass: 1.0\n  shape: sphere\n  geometry: {radius: 0.1}\n  location:\n"
            "    position: {x: " +
            std::to_string(0.5 * (i % 20)) + ", y: " + std::to_string(0.5 * (i / 20)) +
            ", z: 1.0}\n";
  return text;
}

TEST(Capacity, AChainOf200LinksIsReadAndCommandedThroughTheHub) {
  afhub::testing::ModelFolder folder;
  const std::string model = folder.write("chain.yaml", chain_model(200));
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub({"run", model, "--no-autostart"}, log));
  const BodyEntry entry =
      wait_for_body("capacity/chain/base", "capacity_test", monotonic_ns() + 20'000'000'000LL);
  ASSERT_EQ(entry.joint_names.size(), 200u) << read_file(log);
  EXPECT_EQ(entry.joint_names.front(), "j1");
  EXPECT_EQ(entry.joint_names.back(), "j200");
  BodyClient base(entry);
  ASSERT_TRUE(wait_until([&] { return base.latest_state() != nullptr; }, 10s)) << read_file(log);
  ASSERT_EQ(base.latest_state()->joint_count, 200u);

  // Every joint held at 0 but the last, sent to 0.3 rad, for 2 s at 200 Hz.
  const auto until = std::chrono::steady_clock::now() + 2s;
  while (std::chrono::steady_clock::now() < until) {
    BodyCommand* command = base.loan_command(200);
    ASSERT_NE(command, nullptr);
    for (int j = 0; j < 200; ++j)
      command->joints[j] = {j == 199 ? 0.3 : 0.0, JointCommandType::kPosition};
    base.publish_command(command);
    std::this_thread::sleep_for(5ms);
  }
  const BodyState* state = base.latest_state();
  EXPECT_NEAR(state->joints[199].position, 0.3, 0.03);
  EXPECT_NEAR(state->joints[100].position, 0.0, 0.03);

  // `afhub echo` reads it too, naming all 200 joints.
  const RunResult echo = run_afhub({"echo", "capacity/chain/base", "--count", "1", "--json"});
  EXPECT_EQ(echo.exit_code, 0) << echo.err;
  EXPECT_TRUE(contains(echo.out, "\"j200\"")) << echo.out.substr(0, 400);
  EXPECT_EQ(physics.stop(), 0);
}

TEST(Capacity, ASceneOf400BodiesRunsWithEveryBodyListedAndPublished) {
  afhub::testing::ModelFolder folder;
  const std::string model = folder.write("scene.yaml", scene_model(400));
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub({"run", model, "--no-autostart"}, log));
  CatalogReader catalog;
  catalog.wait(2s);
  ASSERT_TRUE(wait_until([&] { return catalog.channels().size() >= 400; }, 20s))
      << catalog.channels().size() << " bodies listed\n"
      << read_file(log);
  for (const char* name : {"capacity/scene/b0", "capacity/scene/b199", "capacity/scene/b399"}) {
    BodyClient body(name);
    // Published, and stepping: a state past step 0.
    EXPECT_TRUE(wait_until(
        [&] { return body.latest_state() && body.latest_state()->header.sim_step > 0; }, 5s))
        << name;
  }
  const RunResult ls = run_afhub({"ls"});
  EXPECT_TRUE(contains(ls.out, "capacity/scene/b399")) << ls.out.substr(0, 400);
  EXPECT_EQ(physics.stop(), 0);
}

}  // namespace
}  // namespace afhub::test
