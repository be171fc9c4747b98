// `afhub view` beside `afhub run` of the project's arm and a mesh body: what the
// server serves and refuses, the binary pose frames over its WebSocket, joint
// commands only with --allow-commands, and headless Chromium drawing the arm.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>
#include <regex>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub_process.hpp"
#include "pixels.hpp"
#include "strict_json.hpp"
#include "web_client.hpp"

namespace afhub::test {
namespace {

// A 0.1 m cube as an ASCII STL.
std::string cube_stl() {
  const double h = 0.05;
  const double v[8][3] = {{-h, -h, -h}, {h, -h, -h}, {h, h, -h}, {-h, h, -h},
                          {-h, -h, h},  {h, -h, h},  {h, h, h},  {-h, h, h}};
  const int faces[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                            {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  std::string stl = "solid cube\n";
  for (const auto& f : faces) {
    stl += " facet normal 0 0 0\n  outer loop\n";
    for (int i : f)
      stl += "   vertex " + std::to_string(v[i][0]) + " " + std::to_string(v[i][1]) + " " +
             std::to_string(v[i][2]) + "\n";
    stl += "  endloop\n endfacet\n";
  }
  return stl + "endsolid cube\n";
}

const char* kCubeModel = R"(adf version: '1.0'
bodies: [BODY cube]
namespace: /afhub/cube/
BODY cube:
  name: cube
  mass: 0.0
  location:
    position: {x: 0.5, y: 0.3, z: 0.05}
    orientation: {r: 0.0, p: 0.0, y: 0.0}
  mesh: cube.STL
  collision shape: BOX
  collision geometry: {x: 0.1, y: 0.1, z: 0.1}
  color rgba: {r: 0.2, g: 0.5, b: 0.9, a: 1.0}
)";

void write_file(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

struct View {
  std::unique_ptr<ScopedProcess> process;
  int port = 0;
  std::string log;
};

class ViewTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char pattern[] = "/tmp/afhub_view_test_XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
    stl_ = cube_stl();
    write_file(dir_ + "/cube.STL", stl_);
    write_file(dir_ + "/cube.yaml", kCubeModel);
    physics_ = std::make_unique<ScopedProcess>(
        spawn_afhub({"run", std::string(AFHUB_EXAMPLE_MODELS) + "/arm7.yaml", dir_ + "/cube.yaml"},
                    dir_ + "/run.log"));
    connect_to_hub("viewtest", HubPolicy::kRequire);
    catalog_ = std::make_unique<CatalogReader>();
    catalog_->wait(std::chrono::seconds(2));
    // The arm's 8 active bodies (its mount is passive) and the cube.
    ASSERT_TRUE(wait_until([] { return catalog_bodies() >= 9; }, std::chrono::seconds(20)))
        << read_file(dir_ + "/run.log");
  }
  static void TearDownTestSuite() {
    physics_.reset();
    catalog_.reset();
  }

  // Bodies (not devices) the hub's catalog lists.
  static std::uint32_t catalog_bodies() {
    const BodyList& list = catalog_->latest();
    std::uint32_t count = 0;
    for (std::uint32_t i = 0; i < list.body_count; ++i)
      if (list.bodies[i].kind == ChannelKind::kBody) ++count;
    return count;
  }

  // `afhub view --port 0 extra...`, once it says its URL.
  static View start_view(const std::vector<std::string>& extra = {}) {
    View view;
    static int started = 0;
    view.log = dir_ + "/view" + std::to_string(++started) + ".log";
    std::vector<std::string> args = {"view", "--port", "0"};
    args.insert(args.end(), extra.begin(), extra.end());
    view.process = std::make_unique<ScopedProcess>(spawn_afhub(args, view.log));
    const std::regex url("http://127\\.0\\.0\\.1:([0-9]+)/");
    wait_until(
        [&] {
          std::smatch match;
          const std::string text = read_file(view.log);
          if (!std::regex_search(text, match, url)) return false;
          view.port = std::stoi(match[1]);
          return true;
        },
        std::chrono::seconds(10));
    return view;
  }

  static inline std::string dir_, stl_;
  static inline std::unique_ptr<ScopedProcess> physics_;
  static inline std::unique_ptr<CatalogReader> catalog_;
};

// The index of `channel` among the scene's bodies in /scene.json, or -1.
int scene_index(const std::string& json, const std::string& channel) {
  const nlohmann::json bodies = parse_json(json).at("bodies");
  int index = -1;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (bodies.at(i).at("channel") != channel) continue;
    EXPECT_EQ(index, -1) << channel << " listed twice in " << json;
    index = static_cast<int>(i);
  }
  return index;
}

TEST_F(ViewTest, ServesThePageThreeJsAndExactlyTheListedMeshes) {
  View view = start_view();
  ASSERT_GT(view.port, 0) << read_file(view.log);
  const HttpReply page = http_request(view.port, "GET", "/");
  EXPECT_EQ(page.status, 200);
  EXPECT_TRUE(contains(page.body, "/viewer.js"));
  EXPECT_TRUE(contains(page.body, "/viewer.css"));
  // The page's files are viewer/web's, as they were at build time.
  EXPECT_EQ(page.body, read_file(std::string(AFHUB_VIEWER_WEB) + "/index.html"));
  for (const std::string name : {"viewer.js", "viewer.css"}) {
    const HttpReply file = http_request(view.port, "GET", "/" + name);
    EXPECT_EQ(file.status, 200) << name;
    EXPECT_EQ(file.body, read_file(std::string(AFHUB_VIEWER_WEB) + "/" + name)) << name;
  }
  const HttpReply three = http_request(view.port, "GET", "/three/three.min.js");
  EXPECT_EQ(three.status, 200);
  EXPECT_GT(three.body.size(), 100'000U);
  EXPECT_EQ(http_request(view.port, "GET", "/three/OrbitControls.js").status, 200);
  EXPECT_EQ(http_request(view.port, "GET", "/three/STLLoader.js").status, 200);

  HttpReply scene;
  ASSERT_TRUE(wait_until(
      [&] {
        scene = http_request(view.port, "GET", "/scene.json");
        return scene.status == 200 && scene_index(scene.body, "afhub/cube/cube") >= 0;
      },
      std::chrono::seconds(5)))
      << scene.body;
  const int cube = scene_index(scene.body, "afhub/cube/cube");
  const int mount = scene_index(scene.body, "afhub/arm/mount");  // shapes, no mesh
  ASSERT_GE(mount, 0);
  EXPECT_FALSE(contains(scene.body, dir_)) << "the page is told no path of this machine";

  const HttpReply mesh = http_request(view.port, "GET", "/mesh/" + std::to_string(cube));
  EXPECT_EQ(mesh.status, 200);
  EXPECT_EQ(mesh.body, stl_);

  // Refused: anything that is not a listed mesh, however it is spelt.
  for (const std::string& target :
       {"/mesh/" + std::to_string(mount), std::string("/mesh/9999"), std::string("/mesh/-1"),
        std::string("/mesh/../../etc/passwd"), std::string("/mesh/%2e%2e/%2e%2e/etc/passwd"),
        std::string("/mesh/") + std::to_string(cube) + "/../../../etc/passwd",
        "/mesh/" + dir_ + "/cube.STL", std::string("/etc/passwd"),
        std::string("/three/../../../../etc/passwd"), std::string("/three/three.module.js"),
        std::string("/../../etc/passwd")}) {
    const HttpReply reply = http_request(view.port, "GET", target);
    EXPECT_TRUE(reply.status == 404 || reply.status == 403) << target << ": " << reply.status;
    EXPECT_FALSE(contains(reply.body, "root:")) << target;
    EXPECT_FALSE(contains(reply.body, "solid cube")) << target;
  }
  // The sliders' joint names, from the catalog.
  HttpReply joints;
  EXPECT_TRUE(wait_until(
      [&] {
        joints = http_request(view.port, "GET", "/joints.json");
        if (joints.status != 200) return false;
        const nlohmann::json names = parse_json(joints.body);
        return names.contains("afhub/arm/base") && names.at("afhub/arm/base").at(0) == "base-link1";
      },
      std::chrono::seconds(5)))
      << joints.body;
  // Read-only without --allow-commands.
  EXPECT_EQ(http_request(view.port, "GET", "/options.json").body, R"({"commands":false})");
  const HttpReply command =
      http_request(view.port, "POST", "/command?body=afhub/arm/base&joint=0&value=0.5");
  EXPECT_EQ(command.status, 403);
  EXPECT_TRUE(contains(command.body, "--allow-commands"));
  const HttpReply world = http_request(view.port, "POST", "/world?action=pause");
  EXPECT_EQ(world.status, 403);
  EXPECT_TRUE(contains(world.body, "--allow-commands"));
}

TEST_F(ViewTest, StreamsBinaryPoseFramesOfEveryCatalogBodyAtDisplayRate) {
  View view = start_view();
  ASSERT_GT(view.port, 0) << read_file(view.log);
  FrameCounter frames(view.port);
  ASSERT_TRUE(frames.connected());
  ASSERT_TRUE(wait_until([&] { return frames.binary_frames() > 0; }, std::chrono::seconds(5)));
  // Frames keep coming, each as new as the one before it or newer, and the world's
  // time advances in them. Counted, not timed: the rate is printed, not asserted (a
  // loaded machine slows it; the wait only bounds a hang).
  const std::uint64_t before = frames.binary_frames();
  const double sim_time_before = frames.last_sim_time_s();
  const auto start = std::chrono::steady_clock::now();
  EXPECT_TRUE(wait_until(
      [&] {
        return frames.binary_frames() >= before + 60 && frames.last_sim_time_s() > sim_time_before;
      },
      std::chrono::seconds(30)))
      << frames.binary_frames() - before << " frames";
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("pose frames: %.1f per second\n",
              static_cast<double>(frames.binary_frames() - before) / seconds);
  EXPECT_EQ(frames.sim_time_reversals(), 0U) << "a frame older than the one before it";
  EXPECT_EQ(frames.text_frames(), 0U) << "poses travel in binary frames, never as text";

  const std::vector<std::uint8_t> frame = frames.last_frame();
  ASSERT_GE(frame.size(), 32U);
  std::uint32_t magic = 0, entries = 0, listed = 0, blocks = 0;
  std::memcpy(&magic, frame.data(), 4);
  std::memcpy(&entries, frame.data() + 8, 4);
  std::memcpy(&listed, frame.data() + 24, 4);
  std::memcpy(&blocks, frame.data() + 28, 4);
  EXPECT_EQ(magic, 0x31564641U);
  // After the entries, the joint blocks: u16 scene index, u16 count, count x f32.
  // The arm's base carries its 7 joints, link1 6, ... link6 1; the cube none.
  std::size_t at = 32U + 32U * entries;
  std::uint32_t joints = 0;
  for (std::uint32_t b = 0; b < blocks && at + 4 <= frame.size(); ++b) {
    std::uint16_t count = 0;
    std::memcpy(&count, frame.data() + at + 2, 2);
    joints += count;
    at += 4U + 4U * count;
  }
  EXPECT_EQ(blocks, 7U);
  EXPECT_EQ(joints, 7U + 6U + 5U + 4U + 3U + 2U + 1U);
  // Then the soft-body block count: none in this scene.
  std::uint32_t soft_blocks = 1;
  if (frame.size() >= at + 4) std::memcpy(&soft_blocks, frame.data() + at, 4);
  EXPECT_EQ(soft_blocks, 0U);
  EXPECT_EQ(frame.size(), at + 4)
      << "the frame is its header, entries, joint blocks and soft-body blocks";
  EXPECT_EQ(entries, catalog_bodies());
  EXPECT_EQ(listed, catalog_bodies());
  for (std::uint32_t e = 0; e < entries; ++e) {
    float w = 0;
    std::memcpy(&w, frame.data() + 32 + 32 * e + 28, 4);
    float x = 0, y = 0, z = 0;
    std::memcpy(&x, frame.data() + 32 + 32 * e + 16, 4);
    std::memcpy(&y, frame.data() + 32 + 32 * e + 20, 4);
    std::memcpy(&z, frame.data() + 32 + 32 * e + 24, 4);
    EXPECT_NEAR(x * x + y * y + z * z + w * w, 1.0, 1e-3) << "entry " << e;
  }
}

TEST_F(ViewTest, AJointCommandMovesTheJointOnlyWithAllowCommands) {
  View view = start_view({"--allow-commands"});
  ASSERT_GT(view.port, 0) << read_file(view.log);
  EXPECT_TRUE(contains(read_file(view.log), "commands allowed"));
  EXPECT_EQ(http_request(view.port, "GET", "/options.json").body, R"({"commands":true})");
  EXPECT_EQ(
      http_request(view.port, "POST", "/command?body=afhub/arm/base&joint=99&value=0.5").status,
      400);
  EXPECT_EQ(
      http_request(view.port, "POST", "/command?body=afhub/arm/base&joint=0&value=nan").status,
      400);
  EXPECT_EQ(http_request(view.port, "GET", "/command?body=afhub/arm/base&joint=0&value=0.5").status,
            405);
  // World commands: a known action, and a step only while paused.
  const HttpReply unknown = http_request(view.port, "POST", "/world?action=fly");
  EXPECT_EQ(unknown.status, 400);
  EXPECT_TRUE(contains(unknown.body, "pause, resume, step, reset")) << unknown.body;
  const HttpReply step = http_request(view.port, "POST", "/world?action=step");
  EXPECT_EQ(step.status, 400);
  EXPECT_TRUE(contains(step.body, "pause it first")) << step.body;
  EXPECT_EQ(http_request(view.port, "GET", "/world?action=pause").status, 405);
  BodyClient base("afhub/arm/base");
  const double target = 0.6;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  while (std::chrono::steady_clock::now() < until) {
    ASSERT_EQ(http_request(view.port, "POST",
                           "/command?body=afhub/arm/base&joint=0&value=" + std::to_string(target))
                  .status,
              200);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const BodyState* state = nullptr;
  ASSERT_TRUE(wait_until([&] { return (state = base.latest_state()) != nullptr; },
                         std::chrono::seconds(2)));
  EXPECT_NEAR(state->joints[0].position, target, 0.05);
}

// The resident memory of a process, in kB (0 when unknown).
long resident_kb(pid_t pid) {
  const std::string status = read_file("/proc/" + std::to_string(pid) + "/status");
  const std::size_t at = status.find("VmRSS:");
  return at == std::string::npos ? 0 : std::atol(status.c_str() + at + 6);
}

// A page that stops reading (a socket with a tiny receive buffer that never reads)
// neither stalls the frames to the other pages nor makes the viewer hoard frames
// for it: it is dropped.
TEST_F(ViewTest, APageThatStopsReadingDelaysNoOtherAndIsDropped) {
  View view = start_view();
  ASSERT_GT(view.port, 0) << read_file(view.log);
  StuckSocket stuck(view.port);
  ASSERT_TRUE(stuck.connected());
  FrameCounter frames(view.port);
  ASSERT_TRUE(frames.connected());
  // About 20 kB of frames a second fill the stuck socket's buffers within seconds;
  // from then on a write to it blocks.
  std::this_thread::sleep_for(std::chrono::seconds(5));
  const long memory_before = resident_kb(view.process->pid);
  // The reading page keeps getting frames, newer and newer, while the stuck one's
  // writes block (a viewer stalled on it would send none). Counted, not timed.
  const std::uint64_t before = frames.binary_frames();
  const double sim_time_before = frames.last_sim_time_s();
  const auto start = std::chrono::steady_clock::now();
  EXPECT_TRUE(wait_until(
      [&] {
        return frames.binary_frames() >= before + 90 && frames.last_sim_time_s() > sim_time_before;
      },
      std::chrono::seconds(30)))
      << frames.binary_frames() - before << " frames beside the stuck page";
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("pose frames to the reading page beside a stuck one: %.1f per second\n",
              static_cast<double>(frames.binary_frames() - before) / seconds);
  EXPECT_EQ(frames.sim_time_reversals(), 0U) << "a frame older than the one before it";
  // Dropped: its pings went unanswered, or a write to it failed (a few seconds; the
  // sanitize build once took more than 10).
  const auto dropping = std::chrono::steady_clock::now();
  EXPECT_TRUE(wait_until([&] { return stuck.closed_by_server(); }, std::chrono::seconds(30)))
      << "the stuck page's connection is still open after 30 s";
  std::printf("the stuck page was dropped %.1f s after the frames were counted\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - dropping).count());
  const long grown = resident_kb(view.process->pid) - memory_before;
  std::printf("the viewer's memory grew by %ld kB\n", grown);
  EXPECT_LT(grown, 2048);
}

// Runs headless Chromium on `url`; returns its stderr (console messages included).
std::string screenshot(const std::string& url, const std::string& file) {
  const RunResult result = run_command(
      {"chromium", "--headless=new", "--no-sandbox", "--use-gl=swiftshader",
       "--enable-unsafe-swiftshader", "--window-size=800,600", "--virtual-time-budget=4000",
       "--enable-logging=stderr", "--v=0", "--screenshot=" + file, url},
      std::chrono::seconds(90));
  EXPECT_EQ(result.exit_code, 0) << result.err;
  return result.err;
}

TEST_F(ViewTest, ChromiumDrawsTheArmAndItsMotion) {
  View view = start_view();
  ASSERT_GT(view.port, 0) << read_file(view.log);
  ScopedProcess sine(spawn_afhub({"ctl", "sine", "arm/base", "--amplitude", "0.8", "--period", "2"},
                                 dir_ + "/sine.log"));
  const std::string url = "http://127.0.0.1:" + std::to_string(view.port) + "/";
  const std::string first = dir_ + "/first.png", second = dir_ + "/second.png";
  const std::string console = screenshot(url, first);
  EXPECT_FALSE(contains(console, "Uncaught")) << console;
  EXPECT_FALSE(contains(console, "Failed to load resource")) << console;
  // The page's scene holds every body the hub lists (its status line counts them).
  const RunResult dom =
      run_command({"chromium", "--headless=new", "--no-sandbox", "--use-gl=swiftshader",
                   "--enable-unsafe-swiftshader", "--window-size=800,600",
                   "--virtual-time-budget=4000", "--dump-dom", url},
                  std::chrono::seconds(90));
  EXPECT_TRUE(contains(dom.out, ", " + std::to_string(catalog_bodies()) + " live bodies"))
      << dom.out;
  std::this_thread::sleep_for(std::chrono::seconds(1));
  screenshot(url, second);
  const long drawn = pixels({"count", first});
  std::printf("arm pixels: %ld of 480000; ", drawn);
  EXPECT_GT(drawn, 3000) << "the arm is not drawn";
  const long moved = pixels({"differ", first, second});
  std::printf("pixels changed a second later: %ld\n", moved);
  // The status line's clock changes a few hundred pixels; the arm's motion thousands.
  EXPECT_GT(moved, 2000) << "the arm did not move between the screenshots";

  // Paused, the same controller moves nothing: the screenshots stay the same.
  ASSERT_EQ(run_afhub({"world", "pause"}).exit_code, 0);
  const std::string third = dir_ + "/third.png", fourth = dir_ + "/fourth.png";
  screenshot(url, third);
  std::this_thread::sleep_for(std::chrono::seconds(1));
  screenshot(url, fourth);
  EXPECT_EQ(run_afhub({"world", "resume"}).exit_code, 0);
  const long paused_change = pixels({"differ", third, fourth});
  std::printf("pixels changed a second later, paused: %ld\n", paused_change);
  EXPECT_LT(paused_change, 100) << "the scene changed while the world was paused";
}

std::uint32_t frame_word(const std::vector<std::uint8_t>& frame, std::size_t at) {
  std::uint32_t word = 0;
  if (frame.size() >= at + 4) std::memcpy(&word, frame.data() + at, 4);
  return word;
}

// Last: it leaves another physics run (the arm alone) behind.
TEST_F(ViewTest, BodiesGoWithTheirPhysicsAndComeBackWithANewScene) {
  View view = start_view();
  ASSERT_GT(view.port, 0) << read_file(view.log);
  FrameCounter frames(view.port);
  ASSERT_TRUE(frames.connected());
  ASSERT_TRUE(
      wait_until([&] { return frame_word(frames.last_frame(), 8) == 9; }, std::chrono::seconds(5)));
  const std::uint32_t generation = frame_word(frames.last_frame(), 4);
  physics_.reset();
  EXPECT_TRUE(
      wait_until([&] { return frame_word(frames.last_frame(), 8) == 0; }, std::chrono::seconds(10)))
      << "the stopped physics' bodies are still in the frames";
  physics_ = std::make_unique<ScopedProcess>(
      spawn_afhub({"run", std::string(AFHUB_EXAMPLE_MODELS) + "/arm7.yaml"}, dir_ + "/run2.log"));
  EXPECT_TRUE(wait_until(
      [&] {
        const std::vector<std::uint8_t> frame = frames.last_frame();
        return frame_word(frame, 4) != generation && frame_word(frame, 8) == 8;
      },
      std::chrono::seconds(20)))
      << "generation " << frame_word(frames.last_frame(), 4) << ", "
      << frame_word(frames.last_frame(), 8) << " bodies";
  const HttpReply scene = http_request(view.port, "GET", "/scene.json");
  EXPECT_LT(scene_index(scene.body, "afhub/cube/cube"), 0) << "the new scene has no cube";
  EXPECT_GE(scene_index(scene.body, "afhub/arm/link7"), 0);
}

}  // namespace
}  // namespace afhub::test
