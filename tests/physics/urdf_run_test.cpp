// A URDF robot through the tools an ADF robot goes through (issue 29): `afhub run
// robot.urdf` publishes its links, `afhub ls` and `echo` show them, `afhub cmd` and
// `afhub ctl` move a joint (read back from the robot's own state), and `afhub view`'s
// scene lists every link, with the meshes its page loads, each at its <origin>: the
// project's own test arm (tests/physics/urdf/arm.urdf), and the UR5 when
// ../shared/urdf_models is there.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <regex>

#include "afhub/hub/bodies.hpp"
#include "afhub_process.hpp"
#include "model_files.hpp"
#include "strict_json.hpp"
#include "web_client.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

const std::string kModels = AFHUB_URDF_TEST_MODELS;
const std::string kSharedUrdf = AFHUB_SHARED_URDF_MODELS;

// The index of `channel` among /scene.json's bodies, or -1.
int scene_index(const nlohmann::json& scene, const std::string& channel) {
  const nlohmann::json& bodies = scene.at("bodies");
  for (std::size_t i = 0; i < bodies.size(); ++i)
    if (bodies.at(i).at("channel") == channel) return static_cast<int>(i);
  return -1;
}

// A URDF robot `afhub run` simulates from `run_args`, whose root body is `root`.
struct Robot {
  std::vector<std::string> run_args;
  std::string root, joint;         // `joint` turns about the vertical: gravity leaves it be
  std::vector<std::string> links;  // every link's channel
  std::string mesh_link, mesh_format, mesh_file;
  // The mesh link's further visual meshes: where each sits in its frame (x, y, z).
  std::vector<std::array<double, 3>> further_meshes = {};
};

// `afhub cmd` takes `joint` to rest at 0.5 and `afhub ctl sine` (0.3 rad, 4 s period)
// swings it either side of where it is then, read back from the root's state; `afhub view`'s scene
// lists every link, and serves the mesh link's mesh as it is on disk.
void drive_and_view(const Robot& robot) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  std::vector<std::string> run = {"run", "--no-autostart", "--watchdog-hold", robot.root};
  run.insert(run.end(), robot.run_args.begin(), robot.run_args.end());
  ScopedProcess physics(spawn_afhub(run, log));
  BodyClient root(robot.root);
  ASSERT_TRUE(wait_until([&] { return root.latest_state() != nullptr; }, 30s)) << read_file(log);
  const std::size_t joint = root.joint_index(robot.joint);
  auto joint_at = [&] { return root.latest_state()->joints[joint].position; };

  // `afhub ls` lists every link, and `afhub echo` prints the root's state with its joints.
  const RunResult ls = run_afhub({"ls", "--json"});
  ASSERT_EQ(ls.exit_code, 0) << ls.err;
  const nlohmann::json listed = parse_json(ls.out);
  for (const std::string& link : robot.links)
    EXPECT_TRUE(std::any_of(listed.begin(), listed.end(),
                            [&](const nlohmann::json& entry) { return entry.at("body") == link; }))
        << link << " is not in `afhub ls`: " << ls.out;
  const RunResult echo = run_afhub({"echo", robot.root, "-n", "1", "--json"});
  ASSERT_EQ(echo.exit_code, 0) << echo.err;
  const nlohmann::json names = parse_json(echo.out).at("joint_names");
  EXPECT_NE(std::find(names.begin(), names.end(), robot.joint), names.end()) << echo.out;

  {
    ScopedProcess cmd(spawn_afhub({"cmd", robot.root, "--joint", robot.joint + "=0.5"}));
    EXPECT_TRUE(wait_until(
        [&] {
          const JointSample& at = root.latest_state()->joints[joint];
          return std::abs(at.position - 0.5) < 0.03 && std::abs(at.velocity) < 0.05;
        },
        20s))
        << robot.joint << " at " << joint_at() << " under `afhub cmd`\n"
        << read_file(log);
  }
  {  // Once the commands stop, the watchdog holds the joints where they are.
    const double start = joint_at();
    ScopedProcess sine(spawn_afhub(
        {"ctl", "sine", robot.root, "--joints", std::to_string(joint), "--amplitude", "0.3"}));
    double low = start, high = start;
    EXPECT_TRUE(wait_until(
        [&] {
          low = std::min(low, joint_at());
          high = std::max(high, joint_at());
          return low < start - 0.15 && high > start + 0.15;
        },
        20s))
        << "under `afhub ctl sine` " << robot.joint << " went over [" << low << ", " << high
        << "] from " << start;
  }

  const std::string view_log = (folder.dir() / "view.log").string();
  ScopedProcess view(spawn_afhub({"view", "--port", "0"}, view_log));
  int port = 0;
  ASSERT_TRUE(wait_until(
      [&] {
        std::smatch match;
        const std::string text = read_file(view_log);
        static const std::regex url("http://127\\.0\\.0\\.1:([0-9]+)/");
        if (!std::regex_search(text, match, url)) return false;
        port = std::stoi(match[1]);
        return true;
      },
      10s))
      << read_file(view_log);
  nlohmann::json scene;
  ASSERT_TRUE(wait_until(
      [&] {
        const HttpReply reply = http_request(port, "GET", "/scene.json");
        if (reply.status != 200 || reply.body.empty()) return false;  // empty: no scene yet
        scene = parse_json(reply.body);
        return scene_index(scene, robot.root) >= 0;
      },
      10s))
      << read_file(view_log);
  for (const std::string& link : robot.links) EXPECT_GE(scene_index(scene, link), 0) << link;
  const int mesh_link = scene_index(scene, robot.mesh_link);
  ASSERT_GE(mesh_link, 0);
  const nlohmann::json& meshes = scene.at("bodies").at(mesh_link).at("meshes");
  ASSERT_EQ(meshes.size(), 1 + robot.further_meshes.size()) << meshes.dump();
  EXPECT_EQ(meshes.at(0).at("format"), robot.mesh_format);
  for (std::size_t m = 1; m < meshes.size(); ++m)
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(meshes.at(m).at("position").at(k).get<double>(), robot.further_meshes[m - 1][k],
                  1e-9)
          << meshes.dump();
  for (const nlohmann::json& mesh : meshes) {
    const HttpReply file = http_request(port, "GET", "/mesh/" + mesh.at("index").dump());
    EXPECT_EQ(file.status, 200) << mesh.dump();
    EXPECT_EQ(file.body, read_file(robot.mesh_file)) << mesh.dump();
  }
}

// The project's own test arm: it runs without ../shared.
TEST(UrdfRun, CmdCtlAndTheViewerDriveAndShowTheTestArm) {
  const std::string arm = "ambf/env/test_arm/";
  std::vector<std::string> links;
  for (const char* link : {"base", "upper", "fore", "tip", "hand", "tool"})
    links.push_back(arm + link);
  drive_and_view({{kModels + "/arm.urdf"},
                  arm + "base",
                  "yaw",
                  links,
                  arm + "fore",
                  ".obj",
                  kModels + "/meshes/cube.obj",
                  {{0.0, 0.0, 0.2}}});
}

// The UR5 from ../shared, without gravity: on the project's gain caps its arm falls
// under gravity, and its fall can swing the base joint off its target for seconds.
TEST(UrdfRun, CmdCtlAndTheViewerDriveAndShowTheUr5) {
  if (!std::filesystem::is_directory(kSharedUrdf))
    GTEST_SKIP() << "needs the URDF robots, and " << kSharedUrdf << " does not exist";
  const std::string robots = kSharedUrdf + "/example-robot-data/robots/ur_description/";
  const std::string ur5 = "ambf/env/ur5/";
  std::vector<std::string> links;
  for (const char* link : {"world", "base_link", "shoulder_link", "upper_arm_link", "forearm_link",
                           "wrist_1_link", "wrist_2_link", "wrist_3_link"})
    links.push_back(ur5 + link);
  // The page draws STL and OBJ meshes; the UR5's visual meshes are DAE (drawn as markers).
  drive_and_view({{robots + "urdf/ur5_robot.urdf", "--package-path", kSharedUrdf, "--default-gains",
                   "2000,0,100", "--gravity", "0,0,0"},
                  ur5 + "world",
                  "shoulder_pan_joint",
                  links,
                  ur5 + "base_link",
                  ".dae",
                  robots + "meshes/ur5/visual/base.dae"});
}

}  // namespace
}  // namespace afhub::test
