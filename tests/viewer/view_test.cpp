// `afhub view` beside `afhub run` of the project's arm and a mesh body: what the
// server serves and refuses, the binary pose frames over its WebSocket, joint
// commands only with --allow-commands. (view_page_test runs the page in Chromium.)
#include <gtest/gtest.h>
#include <stdlib.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/channel.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/scene.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub/viewer/joint_commander.hpp"
#include "afhub_process.hpp"
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
  std::string token;  // with --allow-commands: the command token in the URL printed
  std::string log;
  // A request's headers: the viewer's Host, and the token when it has one.
  std::string headers() const {
    return "Host: 127.0.0.1:" + std::to_string(port) + "\r\n" +
           (token.empty() ? "" : "X-Afhub-Token: " + token + "\r\n");
  }
  HttpReply post(const std::string& target) const {
    return http_request(port, "POST", target, "", headers());
  }
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
    const std::regex url("http://127\\.0\\.0\\.1:([0-9]+)/(\\?token=([0-9a-f]+))?");
    wait_until(
        [&] {
          std::smatch match;
          const std::string text = read_file(view.log);
          if (!std::regex_search(text, match, url)) return false;
          view.port = std::stoi(match[1]);
          view.token = match[3];
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
  EXPECT_EQ(view.token.size(), 32U) << "the URL printed carries the token: " << read_file(view.log);
  EXPECT_EQ(http_request(view.port, "GET", "/options.json").body, R"({"commands":true})");
  EXPECT_EQ(view.post("/command?body=afhub/arm/base&joint=99&value=0.5").status, 400);
  EXPECT_EQ(view.post("/command?body=afhub/arm/base&joint=0&value=nan").status, 400);
  EXPECT_EQ(view.post("/command?body=afhub/arm/base&joint=0&value=0x10").status, 400);
  EXPECT_EQ(http_request(view.port, "GET", "/command?body=afhub/arm/base&joint=0&value=0.5").status,
            405);
  // World commands: a known action, and a step only while paused.
  const HttpReply unknown = view.post("/world?action=fly");
  EXPECT_EQ(unknown.status, 400);
  EXPECT_TRUE(contains(unknown.body, "pause, resume, step, reset")) << unknown.body;
  const HttpReply step = view.post("/world?action=step");
  EXPECT_EQ(step.status, 400);
  EXPECT_TRUE(contains(step.body, "pause it first")) << step.body;
  EXPECT_EQ(http_request(view.port, "GET", "/world?action=pause").status, 405);
  BodyClient base("afhub/arm/base");
  const double target = 0.6;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  while (std::chrono::steady_clock::now() < until) {
    ASSERT_EQ(
        view.post("/command?body=afhub/arm/base&joint=0&value=" + std::to_string(target)).status,
        200);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const BodyState* state = nullptr;
  ASSERT_TRUE(wait_until([&] { return (state = base.latest_state()) != nullptr; },
                         std::chrono::seconds(2)));
  EXPECT_NEAR(state->joints[0].position, target, 0.05);

  // A world command is answered once the world shows it: a step sent right after a
  // pause's answer finds the world paused, and each step's answer finds it stepped.
  LatestReader<WorldState> world(
      {std::string(kService), std::string(kWorldInstance), std::string(kStateEvent)});
  ASSERT_EQ(view.post("/world?action=pause").status, 200);
  ASSERT_TRUE(world.latest());
  EXPECT_TRUE(world.latest()->paused);
  const std::uint64_t paused_at = world.latest()->header.sim_step;
  for (int i = 1; i <= 3; ++i) {
    const HttpReply stepped = view.post("/world?action=step");
    ASSERT_EQ(stepped.status, 200) << stepped.body;
    EXPECT_GE(world.latest()->header.sim_step, paused_at + i);
  }
  ASSERT_EQ(view.post("/world?action=resume").status, 200);
  EXPECT_FALSE(world.latest()->paused);
  EXPECT_EQ(view.post("/world?action=step").status, 400) << "running again at the answer";
}

// Another site's page in the operator's browser (a cross-site request, or DNS
// rebinding: the attacker's name resolving to 127.0.0.1) can neither command nor read.
TEST_F(ViewTest, CommandsNeedTheTokenAndEveryRequestTheViewersHostAndOrigin) {
  View view = start_view({"--allow-commands"});
  ASSERT_GT(view.port, 0) << read_file(view.log);
  ASSERT_FALSE(view.token.empty()) << read_file(view.log);
  const std::string port = std::to_string(view.port);
  const std::string host = "Host: 127.0.0.1:" + port + "\r\n";
  const std::string token = "X-Afhub-Token: " + view.token + "\r\n";
  const std::string command = "/command?body=afhub/arm/base&joint=99&value=0.5";
  // As a cross-site form or fetch sends them: no token, a guessed one.
  for (const std::string& target : {command, std::string("/world?action=reset")}) {
    const HttpReply none = http_request(view.port, "POST", target, "", host);
    EXPECT_EQ(none.status, 403) << target;
    EXPECT_TRUE(contains(none.body, "token")) << none.body;
    EXPECT_EQ(http_request(view.port, "POST", target, "", host + "X-Afhub-Token: 0123\r\n").status,
              403);
    EXPECT_EQ(http_request(view.port, "POST", target + "&token=" + view.token, "", host).status,
              403)
        << "the token travels in its header only";
  }
  // DNS rebinding: the token is unknown to such a page, and its Host is its own name,
  // refused for every request.
  for (const std::string& target : {command, std::string("/"), std::string("/scene.json")}) {
    const HttpReply rebound = http_request(view.port, target == command ? "POST" : "GET", target,
                                           "", "Host: evil.example:" + port + "\r\n" + token);
    EXPECT_EQ(rebound.status, 403) << target;
    EXPECT_TRUE(contains(rebound.body, "evil.example")) << rebound.body;
  }
  // Another site's page, with the token somehow: its Origin gives it away.
  const HttpReply other = http_request(view.port, "POST", command, "",
                                       host + token + "Origin: http://evil.example\r\n");
  EXPECT_EQ(other.status, 403);
  EXPECT_TRUE(contains(other.body, "http://evil.example")) << other.body;
  // The viewer's own page: its origin, by address or as localhost.
  EXPECT_EQ(http_request(view.port, "POST", command, "",
                         host + token + "Origin: http://127.0.0.1:" + port + "\r\n")
                .status,
            400)
      << "served (a joint index out of range)";
  EXPECT_EQ(http_request(view.port, "POST", command, "",
                         "Host: localhost:" + port + "\r\n" + token +
                             "Origin: http://localhost:" + port + "\r\n")
                .status,
            400);
  // The WebSocket: another site's page is refused at the handshake.
  const auto handshake = [&](const std::string& origin) {
    const int fd = connect_from("", view.port);
    if (fd < 0) return std::string("no connection");
    const std::string upgrade = "GET /ws HTTP/1.1\r\n" + host +
                                "Upgrade: websocket\r\nConnection: Upgrade\r\n"
                                "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                                "Sec-WebSocket-Version: 13\r\nOrigin: " +
                                origin + "\r\n\r\n";
    std::string reply;
    if (write(fd, upgrade.data(), upgrade.size()) == static_cast<ssize_t>(upgrade.size())) {
      char byte;
      while (reply.find("\r\n\r\n") == std::string::npos && read(fd, &byte, 1) == 1) reply += byte;
    }
    close(fd);
    return reply;
  };
  EXPECT_TRUE(contains(handshake("http://evil.example"), " 403 "));
  EXPECT_TRUE(contains(handshake("http://127.0.0.1:" + port), " 101 "));
}

// A loop of requests naming made-up bodies is refused without opening a client for
// any: only catalog bodies are opened, and a body's client takes no port of its own
// (its slots are entries in its process's blocks): iceoryx's 512 publisher ports
// stay free however many bodies a viewer commands.
TEST_F(ViewTest, MadeUpBodyNamesTakeNoPorts) {
  View view = start_view({"--allow-commands"});
  ASSERT_GT(view.port, 0) << read_file(view.log);
  // The viewer's own ports, and a client for the base, taken.
  ASSERT_EQ(view.post("/command?body=afhub/arm/base&joint=99&value=0").status, 400);
  std::uint32_t before = 0;
  ASSERT_TRUE(wait_until(
      [&] {
        const std::optional<std::uint32_t> first = free_publisher_ports(std::chrono::seconds(1));
        std::this_thread::sleep_for(std::chrono::milliseconds(300));  // held still that long
        const std::optional<std::uint32_t> second = free_publisher_ports(std::chrono::seconds(1));
        before = second.value_or(0);
        return first && second && *first == *second;
      },
      std::chrono::seconds(10)));
  for (int i = 0; i < 40; ++i) {
    const HttpReply reply =
        view.post("/command?body=made/up/body" + std::to_string(i) + "&joint=0&value=0");
    EXPECT_EQ(reply.status, 400);
    EXPECT_TRUE(contains(reply.body, "not a body the catalog lists")) << reply.body;
  }
  // Catalog bodies' clients, opened after them, and a command sent through each.
  for (const char* body : {"afhub/arm/link1", "afhub/arm/link2", "afhub/arm/link3"})
    EXPECT_EQ(view.post(std::string("/command?body=") + body + "&joint=0&value=0").status, 200)
        << body;
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // the hub's health, twice
  const std::uint32_t after = free_publisher_ports(std::chrono::seconds(1)).value_or(0);
  // At most one: the block of the viewer's command slots, if its first command opened it.
  EXPECT_GE(after + 1, before) << "the made-up names, or the bodies' clients, took ports";
}

// The commander keeps at most its cap of BodyClients, the least recently used closed.
TEST_F(ViewTest, TheJointCommanderKeepsAtMostItsCapOfClients) {
  viewer::JointCommander commander(2);
  const std::vector<std::string> bodies = catalog_->channels();
  commander.set_bodies(bodies);
  const std::string made_up = commander.run("body=made/up&joint=0&value=0");
  EXPECT_TRUE(contains(made_up, "not a body the catalog"))
      << made_up << "; the catalog: " << ::testing::PrintToString(bodies);
  EXPECT_EQ(commander.open_clients(), 0U);
  std::size_t bodies_tried = 0;
  for (const std::string& body : bodies) {
    if (body.find("arm/") == std::string::npos) continue;
    // A joint out of range: the body's client is opened, nothing is sent.
    EXPECT_TRUE(contains(commander.run("body=" + body + "&joint=999&value=0"), "joint"));
    EXPECT_LE(commander.open_clients(), 2U);
    ++bodies_tried;
  }
  EXPECT_GE(bodies_tried, 7U);
  EXPECT_EQ(commander.open_clients(), 2U);
  commander.set_bodies({});
  EXPECT_EQ(commander.open_clients(), 0U) << "bodies that left the catalog are closed";
}

// Other machines may command only when the user says so, and are told it is insecure.
TEST_F(ViewTest, CommandsFromOtherMachinesNeedInsecureRemoteCommands) {
  const RunResult refused = run_afhub(
      {"view", "--port", "0", "--bind", "0.0.0.0", "--allow-commands"}, std::chrono::seconds(10));
  EXPECT_EQ(refused.exit_code, 1) << "refused at once (-1: still running after 10 s)";
  EXPECT_TRUE(contains(refused.err, "would let other machines drive the robot")) << refused.err;
  EXPECT_TRUE(contains(refused.err, "add --insecure-remote-commands")) << refused.err;
  const std::string log = dir_ + "/insecure.log";
  ScopedProcess insecure(spawn_afhub({"view", "--port", "0", "--bind", "0.0.0.0",
                                      "--allow-commands", "--insecure-remote-commands"},
                                     log));
  EXPECT_TRUE(wait_until([&] { return contains(read_file(log), "http://0.0.0.0:"); },
                         std::chrono::seconds(10)))
      << read_file(log);
  EXPECT_TRUE(contains(read_file(log), "INSECURE")) << read_file(log);
  // Read-only on every address is as before.
  const std::string read_only = dir_ + "/read_only_remote.log";
  ScopedProcess watching(spawn_afhub({"view", "--port", "0", "--bind", "0.0.0.0"}, read_only));
  EXPECT_TRUE(wait_until([&] { return contains(read_file(read_only), "read-only"); },
                         std::chrono::seconds(10)))
      << read_file(read_only);
}

// A scene any member of the hub's group may publish (here on a world of its own) names
// files: /mesh/N serves only regular mesh files within the model folders it lists.
TEST_F(ViewTest, AScenesMeshesAreServedOnlyAsMeshFilesWithinItsModelFolders) {
  namespace fs = std::filesystem;
  const std::string model = dir_ + "/crafted_model", home = dir_ + "/crafted_home";
  fs::create_directories(model + "/meshes");
  fs::create_directories(home + "/.ssh");
  write_file(model + "/meshes/part.stl", stl_);
  write_file(home + "/.ssh/id_ed25519", "PRIVATE KEY");
  write_file(home + "/photo.stl", "PHOTO BYTES");
  fs::create_symlink(home + "/.ssh/id_ed25519", model + "/meshes/key.stl");
  ASSERT_EQ(mkfifo((model + "/meshes/fifo.stl").c_str(), 0600), 0);
  const std::vector<std::string> meshes = {model + "/meshes/part.stl", home + "/.ssh/id_ed25519",
                                           home + "/photo.stl",        model + "/meshes/key.stl",
                                           model + "/meshes/fifo.stl", "/etc/passwd"};
  Writer<SceneDescription> writer(
      {std::string(kService), world_instance("crafted"), std::string(kSceneEvent)});
  SceneDescription* scene = writer.loan(scene_description_bytes(meshes.size()));
  ASSERT_NE(scene, nullptr);
  scene->body_count = static_cast<std::uint32_t>(meshes.size());
  for (std::size_t b = 0; b < meshes.size(); ++b) {
    set_name(scene->bodies[b].channel, "crafted/body" + std::to_string(b));
    set_name(scene->bodies[b].mesh, meshes[b]);
  }
  // The same files again as body 0's further meshes: /mesh/6 to /mesh/11.
  scene->mesh_part_count = static_cast<std::uint32_t>(meshes.size());
  for (std::size_t p = 0; p < meshes.size(); ++p) set_name(scene->mesh_parts[p].mesh, meshes[p]);
  scene->model_folder_count = 1;
  set_name(scene->model_folders[0], model);
  writer.publish(scene);

  View view = start_view({"--namespace", "crafted"});
  ASSERT_GT(view.port, 0) << read_file(view.log);
  ASSERT_TRUE(wait_until(
      [&] {
        return scene_index(http_request(view.port, "GET", "/scene.json").body, "crafted/body5") ==
               5;
      },
      std::chrono::seconds(10)));
  for (std::size_t m = 0; m < 2 * meshes.size(); ++m) {
    const std::string& file = meshes[m % meshes.size()];
    const HttpReply reply = http_request(view.port, "GET", "/mesh/" + std::to_string(m));
    if (m % meshes.size() == 0) {
      EXPECT_EQ(reply.status, 200) << m;
      EXPECT_EQ(reply.body, stl_) << m;
      continue;
    }
    EXPECT_EQ(reply.status, 403) << file << ": " << reply.body;
    EXPECT_FALSE(contains(reply.body, "PRIVATE KEY")) << file;
    EXPECT_FALSE(contains(reply.body, "PHOTO BYTES")) << file;
    EXPECT_FALSE(contains(reply.body, "root:")) << file;
    EXPECT_FALSE(contains(reply.body, dir_)) << "a reply names no path";
  }
  EXPECT_EQ(http_request(view.port, "GET", "/mesh/" + std::to_string(2 * meshes.size())).status,
            404);
}

// A viewer started before its world's physics serves a scene of nothing (valid JSON,
// generation 0), then the physics' scene as a later generation. (It served an empty
// body, which neither a page nor a test could parse.)
TEST_F(ViewTest, BeforeAnySceneTheViewerServesOneOfNothing) {
  View view = start_view({"--namespace", "later"});
  ASSERT_GT(view.port, 0) << read_file(view.log);
  const HttpReply before = http_request(view.port, "GET", "/scene.json");
  EXPECT_EQ(before.status, 200);
  const nlohmann::json nothing = parse_json(before.body);
  EXPECT_EQ(nothing.at("generation"), 0);
  EXPECT_TRUE(nothing.at("bodies").empty()) << before.body;
  EXPECT_TRUE(nothing.at("lights").empty()) << before.body;

  Writer<SceneDescription> writer(
      {std::string(kService), world_instance("later"), std::string(kSceneEvent)});
  SceneDescription* scene = writer.loan(scene_description_bytes(2));
  ASSERT_NE(scene, nullptr);
  scene->body_count = 2;
  set_name(scene->bodies[0].channel, "later/first");
  set_name(scene->bodies[1].channel, "later/second");
  writer.publish(scene);
  nlohmann::json after;
  ASSERT_TRUE(wait_until(
      [&] {
        after = parse_json(http_request(view.port, "GET", "/scene.json").body);
        return after.at("bodies").size() == 2;
      },
      std::chrono::seconds(10)))
      << after.dump();
  EXPECT_GT(after.at("generation").get<int>(), 0);
  EXPECT_EQ(scene_index(after.dump(), "later/second"), 1);
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
