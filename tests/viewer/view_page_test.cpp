// The viewer's page in headless Chromium, driven over the DevTools protocol, beside
// `afhub run` of the example scene (the arm, the floor and the world file's three
// cameras): the scene drawn, every listed body live, inspect a clicked body's joint
// positions and plot them, move a joint with a slider (only with --allow-commands),
// pause, step and reset with the buttons (the drawn arm moving, then still), open
// a camera's viewport by name, and mark the cameras input devices pair.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <regex>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub_process.hpp"
#include "devtools_client.hpp"
#include "pixels.hpp"
#include "shared_models.hpp"
#include "web_client.hpp"
#include "world_reader.hpp"

namespace afhub::test {
namespace {

const std::string kModels = AFHUB_EXAMPLE_MODELS;

// An input device file pairing the world's camera "rcm_close" by its name, and
// "overview" by its block key in the world file, as AMBF's files do.
std::string paired_devices() {
  const auto device = [](const std::string& name, const std::string& camera) {
    return name + ":\n  hardware name: PHANTOM Omni\n  haptic gain: {linear: 0.0, angular: 0.0}\n" +
           "  simulated multibody: " + kModels + "/gripper.yaml\n" +
           "  root link: /afhub/gripper/BODY palm\n  pair cameras: [" + camera + "]\n";
  };
  return "input devices: [Test Touch, Key Touch]\n" + device("Test Touch", "rcm_close") +
         device("Key Touch", "camera_overview");
}

// A value the page returned: NaN, or "", when it returned none (problem() says why).
double number_of(const nlohmann::json& value) {
  return value.is_number() ? value.get<double>() : NAN;
}
std::string string_of(const nlohmann::json& value) {
  return value.is_string() ? value.get<std::string>() : "";
}

struct View {
  std::unique_ptr<ScopedProcess> process;
  std::string url;   // http://127.0.0.1:PORT
  std::string page;  // the URL printed: url + "/", and "?token=..." with --allow-commands
  int port = 0;
};

class ViewPageTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ASSERT_NO_FATAL_FAILURE(start_physics("0", "afhub/arm/base"));
    std::ofstream(dir_ + "/input_devices.yaml") << paired_devices();
    read_only_ = start_view({"--input-devices", dir_ + "/input_devices.yaml"});
    commands_ = start_view({"--allow-commands"});
    browser_ = std::make_unique<Browser>(dir_);
    ASSERT_TRUE(browser_->ready()) << browser_->problem();
  }
  // A scratch directory, and `afhub run` of the example launch file's config
  // `launch_index` until `body` publishes.
  static void start_physics(const std::string& launch_index, const std::string& body) {
    char pattern[] = "/tmp/afhub_view_page_test_XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
    physics_ = std::make_unique<ScopedProcess>(spawn_afhub(
        {"run", "--launch", kModels + "/launch.yaml", "-l", launch_index}, dir_ + "/run.log"));
    connect_to_hub("viewpagetest", HubPolicy::kRequire);
    base_ = std::make_unique<BodyClient>(body);
    ASSERT_TRUE(
        wait_until([] { return base_->latest_state() != nullptr; }, std::chrono::seconds(20)))
        << read_file(dir_ + "/run.log");
  }
  static void TearDownTestSuite() {
    browser_.reset();
    read_only_.process.reset();
    commands_.process.reset();
    base_.reset();
    physics_.reset();
  }

  static View start_view(const std::vector<std::string>& extra) {
    View view;
    static int started = 0;
    const std::string log = dir_ + "/view" + std::to_string(++started) + ".log";
    std::vector<std::string> args = {"view", "--port", "0"};
    args.insert(args.end(), extra.begin(), extra.end());
    view.process = std::make_unique<ScopedProcess>(spawn_afhub(args, log));
    const std::regex url("http://127\\.0\\.0\\.1:([0-9]+)/(\\?token=[0-9a-f]+)?");
    wait_until(
        [&] {
          std::smatch match;
          const std::string text = read_file(log);
          if (!std::regex_search(text, match, url)) return false;
          view.port = std::stoi(match[1]);
          view.page = match[0];
          return true;
        },
        std::chrono::seconds(10));
    view.url = "http://127.0.0.1:" + std::to_string(view.port);
    EXPECT_GT(view.port, 0) << read_file(log);
    return view;
  }

  // Loads `url` on a clean console. The page before is left for a blank one first: its
  // viewer may be gone (a test's own ended with it), and its retries would log errors
  // that arrive after a clear made while it was still open.
  static void go_to(const std::string& url) {
    ASSERT_TRUE(browser_->navigate("about:blank")) << browser_->problem();
    browser_->clear_console();
    ASSERT_TRUE(browser_->navigate(url)) << browser_->problem();
  }

  // Opens `url` and waits until the page draws live poses.
  static void open(const std::string& url) {
    ASSERT_NO_FATAL_FAILURE(go_to(url));
    ASSERT_TRUE(wait_until([] { return browser_->evaluate("window.afhub.frames > 10") == true; },
                           std::chrono::seconds(30)))
        << browser_->problem();
  }

  // No uncaught exception, console error or failed load since open().
  static void expect_clean_console() {
    for (const std::string& message : browser_->console()) {
      EXPECT_FALSE(contains(message, "exceptionThrown")) << message;
      EXPECT_FALSE(contains(message, "\"level\":\"error\"")) << message;
    }
  }

  // Clicks where `channel`'s body is drawn and nothing else is near; false (said on
  // stdout) when no pixel shows it now: a swinging arm can hide it for a moment.
  static bool click_body(const std::string& channel) {
    // A whole pixel of the screen whose first hit is this body, and its neighbours' 3 px
    // away too: its box's centre may be behind another link once the arm has moved, or
    // under a panel the page shows (a click there never reaches the scene); and a point
    // at the body's edge, where the click may land a fraction of a pixel off, can pick
    // what lies beside it (a fresh CI run clicked the base for 15 s and kept link3).
    const nlohmann::json at = browser_->evaluate(
        "(() => { const b = bodies.find((b) => b.userData.channel === '" + channel +
        "'); const box = new THREE.Box3().setFromObject(b); const r = new THREE.Raycaster();"
        " const owner = (o) => { while (o && o.userData.channel === undefined) o = o.parent;"
        " return o; };"
        " const shows = (x, y) => { r.setFromCamera(new THREE.Vector2(x / innerWidth * 2 - 1,"
        "   -(y / innerHeight) * 2 + 1), camera);"
        "  const hit = r.intersectObjects(bodies, true)[0];"
        "  return hit && owner(hit.object) === b &&"
        "   document.elementFromPoint(x, y) === renderer.domElement; };"
        " for (let i = 0; i <= 8; i++) for (let j = 0; j <= 8; j++) for (let k = 0; k <= 8; k++) {"
        "  const p = new THREE.Vector3(box.min.x + (box.max.x - box.min.x) * (0.1 + 0.1 * i),"
        "   box.min.y + (box.max.y - box.min.y) * (0.1 + 0.1 * j),"
        "   box.min.z + (box.max.z - box.min.z) * (0.1 + 0.1 * k)).project(camera);"
        "  const x = Math.round((p.x + 1) / 2 * innerWidth),"
        "   y = Math.round((1 - p.y) / 2 * innerHeight);"
        "  if ([[0, 0], [-3, 0], [3, 0], [0, -3], [0, 3]].every(([dx, dy]) =>"
        "      shows(x + dx, y + dy))) return [x, y]; }"
        " return 'no pixel shows ' + b.userData.channel + ' with 3 px of it around'; })()");
    if (!at.is_array() || at.size() != 2U) {
      std::printf("not clicked: %s %s\n", at.dump().c_str(), browser_->problem().c_str());
      return false;
    }
    browser_->click(at.at(0).get<double>(), at.at(1).get<double>());
    return true;
  }

  // Clicks the page element `id` (a real mouse click at its centre).
  static void click_element(const std::string& id) {
    const nlohmann::json at = browser_->evaluate(
        "(() => { const r = document.getElementById('" + id +
        "').getBoundingClientRect(); return [r.x + r.width / 2, r.y + r.height / 2]; })()");
    ASSERT_EQ(at.size(), 2U) << browser_->problem();
    browser_->click(at.at(0).get<double>(), at.at(1).get<double>());
  }

  static std::string text_of(const std::string& selector) {
    return string_of(browser_->evaluate("document.querySelector('" + selector + "').textContent"));
  }

  static double base_joint(std::size_t joint) {
    const BodyState* state = base_->latest_state();
    return state && joint < state->joint_count ? state->joints[joint].position : NAN;
  }

  static inline std::string dir_;
  static inline std::unique_ptr<ScopedProcess> physics_;
  static inline std::unique_ptr<BodyClient> base_;
  static inline View read_only_, commands_;
  static inline std::unique_ptr<Browser> browser_;
};

// A page opened before its world's physics runs shows an empty world, live, and the
// scene once a physics comes. (The viewer served an empty body as the scene before a
// physics: the page threw on it and never connected.)
TEST_F(ViewPageTest, APageOpenedBeforeThePhysicsDrawsItsSceneWhenItComes) {
  const View view = start_view({"--namespace", "later"});
  ASSERT_NO_FATAL_FAILURE(go_to(view.url + "/"));
  ASSERT_TRUE(wait_until([] { return browser_->evaluate("window.afhub.frames > 10") == true; },
                         std::chrono::seconds(30)))
      << "frames drawn: " << browser_->evaluate("window.afhub.frames").dump() << " "
      << browser_->problem();
  EXPECT_EQ(browser_->evaluate("window.afhub.sceneBodies"), 0);

  ScopedProcess physics(
      spawn_afhub({"run", "--namespace", "later", kModels + "/arm7.yaml"}, dir_ + "/later.log"));
  ASSERT_TRUE(wait_until(
      [] {
        return browser_->evaluate(
                   "window.afhub.sceneBodies > 0 && window.afhub.bodiesInFrame > 0") == true;
      },
      std::chrono::seconds(30)))
      << read_file(dir_ + "/later.log") << browser_->problem();
  expect_clean_console();
}

TEST_F(ViewPageTest, AClickedBodyShowsItsJointPositionsAndPlotsThem) {
  ScopedProcess sine(spawn_afhub({"ctl", "sine", "arm/base", "--amplitude", "0.8", "--period", "2"},
                                 dir_ + "/sine_inspect.log"));
  open(read_only_.url + "/");
  ASSERT_TRUE(wait_until([] { return click_body("afhub/arm/base"); }, std::chrono::seconds(15)));
  ASSERT_TRUE(wait_until([] { return contains(text_of("#pose"), "afhub/arm/base"); },
                         std::chrono::seconds(5)))
      << "the inspect panel shows: " << text_of("#inspect");
  // The joint names from the catalog, and each joint's live position: compared
  // paused, so that the page and the test read the same state.
  // The sine under way (a condition, not a time: paused near its zero crossing, the
  // joint would read about 0 however long it ran).
  ASSERT_TRUE(wait_until([] { return std::abs(base_joint(0)) > 0.05; }, std::chrono::seconds(10)))
      << "the sine never moved joint 0";
  ASSERT_EQ(run_afhub({"world", "pause"}).exit_code, 0);
  // The page shows the paused state once the frames on their way are drawn (waited
  // for: a busy machine's browser draws late).
  std::string shown;
  double value = NAN;
  bool parsed = false;
  const bool same = wait_until(
      [&] {
        shown = text_of("#joints .value");
        char* end = nullptr;
        value = std::strtod(shown.c_str(), &end);
        parsed = !shown.empty() && *end == '\0';
        return parsed && std::abs(value - base_joint(0)) < 1e-3;
      },
      std::chrono::seconds(10));
  const std::string joints = text_of("#joints");
  EXPECT_TRUE(contains(joints, "base-link1")) << joints;
  EXPECT_TRUE(contains(joints, "link6-link7")) << joints;
  EXPECT_TRUE(parsed) << "joint 0's value: '" << shown << "'";
  EXPECT_TRUE(same) << "the page shows " << value << ", the paused joint is at " << base_joint(0)
                    << "\n"
                    << joints;
  const std::string pose = text_of("#pose");
  EXPECT_TRUE(contains(pose, "position ") && contains(pose, "orientation ")) << pose;
  ASSERT_EQ(run_afhub({"world", "resume"}).exit_code, 0);

  // The plot: its traces' colours drawn in its canvas a second later (still joints
  // draw flat lines over each other, so any trace's colour counts).
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  browser_->screenshot(dir_ + "/inspect.png");  // left for a look
  const nlohmann::json drawn = browser_->evaluate(R"((() => {
      const c = document.getElementById('plot');
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      const colours = plotColors.map((h) => [1, 3, 5].map((i) => parseInt(h.substr(i, 2), 16)));
      let traced = 0, background = 0;
      for (let i = 0; i < d.length; i += 4) {
        if (colours.some((c) => c.every((v, k) => Math.abs(d[i + k] - v) < 24))) traced++;
        if (d[i] === 0x10 && d[i + 1] === 0x15 && d[i + 2] === 0x1b) background++;
      }
      return [traced, d.length / 4 - background];
    })())");
  ASSERT_EQ(drawn.size(), 2U) << browser_->problem();
  const double traced = drawn.at(0).get<double>(), not_background = drawn.at(1).get<double>();
  std::printf("plot: %.0f pixels of the joints' traces, %.0f not background\n", traced,
              not_background);
  EXPECT_GT(traced, 100) << "no joint's trace is drawn";
  EXPECT_GT(not_background, 500);
  expect_clean_console();
}

TEST_F(ViewPageTest, ASliderMovesTheJointOnlyWithAllowCommands) {
  ASSERT_TRUE(contains(commands_.page, "?token=")) << commands_.page;
  open(commands_.page);
  // The arm may still swing (the last test's sine released by the watchdog): a link can
  // move in front of the point clicked before the click lands (once in a loaded CI run:
  // link6, one slider), so the base is clicked until its seven sliders show.
  ASSERT_TRUE(wait_until(
      [] {
        if (!click_body("afhub/arm/base")) return false;
        return wait_until(
            [] {
              return number_of(browser_->evaluate(
                         "document.querySelectorAll('#drive input').length")) >= 7;
            },
            std::chrono::seconds(1));
      },
      std::chrono::seconds(15)))
      << "no sliders: " << text_of("#drive");
  const double target = base_joint(0) > 0.3 ? -0.5 : 0.6;
  EXPECT_EQ(browser_->evaluate("(() => { const s = document.querySelector('#drive "
                               "input[data-joint=\"0\"]'); s.value = " +
                               std::to_string(target) +
                               "; s.dispatchEvent(new Event('input')); return 'moved'; })()"),
            "moved")
      << browser_->problem();
  EXPECT_TRUE(
      wait_until([&] { return std::abs(base_joint(0) - target) < 0.05; }, std::chrono::seconds(5)))
      << "joint 0 is at " << base_joint(0) << ", the slider asked " << target;
  expect_clean_console();

  // Read-only: no sliders nor world buttons, and the same request is refused.
  open(read_only_.url + "/");
  // Released by the watchdog, the arm swings: a link can move in front of the point
  // clicked before the click lands (once: link3), so the base is clicked until inspected.
  // The page shows a click a frame later, and its panel may then cover the base (a fresh
  // CI run clicked it, looked at once, and never found it uncovered again): each click is
  // given a second to show.
  const auto inspected = [] { return contains(text_of("#pose"), "afhub/arm/base"); };
  ASSERT_TRUE(wait_until(
      [&] {
        return inspected() ||
               (click_body("afhub/arm/base") && wait_until(inspected, std::chrono::seconds(1)));
      },
      std::chrono::seconds(15)))
      << "inspected: " << text_of("#pose");
  EXPECT_EQ(browser_->evaluate("document.querySelectorAll('#drive input, #world button').length"),
            0);
  const double refused_target = -target;
  // Released by the physics' watchdog, the arm falls, and its links' fall swings joint 0
  // (under load by most of a radian in a second): measured once the arm has come to rest,
  // so that a command, which would take joint 0 most of the way to the refused target
  // within the second, is what moves it.
  EXPECT_TRUE(wait_until(
      [] {
        const BodyState* state = base_->latest_state();
        if (!state) return false;
        for (std::size_t j = 0; j < state->joint_count; ++j)
          if (std::abs(state->joints[j].velocity) > 0.02) return false;
        return true;
      },
      std::chrono::seconds(20)))
      << "the released arm never came to rest";
  const double before = base_joint(0);
  const std::string post =
      "fetch('/command?body=afhub/arm/base&joint=0&value=" + std::to_string(refused_target) +
      "', {method: 'POST'}).then((r) => r.status)";
  EXPECT_EQ(browser_->evaluate(post), 403);
  EXPECT_EQ(
      browser_->evaluate("fetch('/world?action=pause', {method: 'POST'}).then((r) => r.status)"),
      403);
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const double approached =
      std::abs(before - refused_target) - std::abs(base_joint(0) - refused_target);
  EXPECT_LT(approached, 0.5) << "a read-only page moved the joint from " << before << " to "
                             << base_joint(0) << " (refused target " << refused_target << ")";

  // The commanding viewer's page opened without its token (as another site's page
  // would post): the page says so, and a command is refused.
  open(commands_.url + "/");
  EXPECT_TRUE(contains(text_of("#token-needed"), "token")) << text_of("#world");
  EXPECT_EQ(browser_->evaluate(post), 403);
  EXPECT_EQ(
      browser_->evaluate("fetch('/world?action=pause', {method: 'POST'}).then((r) => r.status)"),
      403);
}

TEST_F(ViewPageTest, PauseStepAndResetButtonsDriveTheWorld) {
  ScopedProcess sine(spawn_afhub({"ctl", "sine", "arm/base", "--amplitude", "0.8", "--period", "2"},
                                 dir_ + "/sine.log"));
  open(commands_.page);
  // A camera's link keeps the token: its viewport commands too.
  EXPECT_TRUE(contains(string_of(browser_->evaluate("document.querySelector('#cameras a').href")),
                       commands_.page.substr(commands_.page.find("token="))));
  LatestReader<WorldState> world = world_reader();
  ASSERT_TRUE(wait_until([&] { return world.latest() != nullptr; }, std::chrono::seconds(5)));
  ASSERT_FALSE(world.latest()->paused);
  std::string shots[4] = {dir_ + "/running1.png", dir_ + "/running2.png", dir_ + "/paused1.png",
                          dir_ + "/paused2.png"};
  // Running, the controller moves the arm: a later screenshot differs (how much in a
  // given second depends on where the sine is, and on the machine's load: waited for).
  ASSERT_TRUE(browser_->screenshot(shots[0]));
  const long drawn = pixels({"count", shots[0]});
  std::printf("pixels drawn over the background: %ld of 480000\n", drawn);
  EXPECT_GT(drawn, 3000) << "the scene is not drawn";
  // Every body the hub lists is live in the page (its status line counts them).
  CatalogReader catalog;
  catalog.wait(std::chrono::seconds(2));
  std::uint32_t listed = 0;
  for (std::uint32_t i = 0; i < catalog.latest().body_count; ++i)
    if (catalog.latest().bodies[i].kind == ChannelKind::kBody) ++listed;
  const std::string live = ", " + std::to_string(listed) + " live bodies";
  EXPECT_TRUE(
      wait_until([&] { return contains(text_of("#status"), live); }, std::chrono::seconds(5)))
      << text_of("#status") << " (the hub lists " << listed << ")";
  long running = 0;
  wait_until(
      [&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
        running = browser_->screenshot(shots[1]) ? pixels({"differ", shots[0], shots[1]}) : 0;
        return running > 500;
      },
      std::chrono::seconds(15));

  click_element("pause");
  ASSERT_TRUE(wait_until([&] { return world.latest()->paused != 0; }, std::chrono::seconds(5)))
      << "the pause button did not pause the world";
  ASSERT_TRUE(wait_until([] { return text_of("#pause") == "resume"; }, std::chrono::seconds(5)));
  // The last frames drawn: two screenshots 300 ms apart the same (a busy machine's
  // browser draws late); a page that went on moving never gets there.
  ASSERT_TRUE(browser_->screenshot(shots[2]));
  for (int look = 0; look < 30; ++look) {  // up to 9 s
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ASSERT_TRUE(browser_->screenshot(shots[3]));
    if (pixels({"differ", shots[2], shots[3]}) == 0) break;
    std::swap(shots[2], shots[3]);
  }
  ASSERT_TRUE(browser_->screenshot(shots[2]));
  std::this_thread::sleep_for(std::chrono::seconds(1));
  ASSERT_TRUE(browser_->screenshot(shots[3]));
  const long paused = pixels({"differ", shots[2], shots[3]});
  std::printf("pixels changed a second later: running %ld, paused %ld\n", running, paused);
  EXPECT_GT(running, 500) << "the arm did not move while running";
  EXPECT_EQ(paused, 0) << "the page changed while the world was paused";

  // Step: one step, and the world stays paused.
  const std::uint64_t before = world.latest()->header.sim_step;
  click_element("step");
  EXPECT_TRUE(wait_until([&] { return world.latest()->header.sim_step != before; },
                         std::chrono::seconds(5)));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(world.latest()->header.sim_step, before + 1);
  EXPECT_TRUE(world.latest()->paused);

  // Reset: the step count goes back to 0.
  click_element("reset");
  EXPECT_TRUE(
      wait_until([&] { return world.latest()->header.sim_step < before; }, std::chrono::seconds(5)))
      << "still at step " << world.latest()->header.sim_step;

  click_element("pause");  // now "resume"
  EXPECT_TRUE(wait_until([&] { return world.latest()->paused == 0; }, std::chrono::seconds(5)));
  expect_clean_console();
}

TEST_F(ViewPageTest, ACameraNameOpensItsViewportAndPairedCamerasAreMarked) {
  // The world file's cameras, as the scene lists them.
  const nlohmann::json scene = parse_json(http_request(read_only_.port, "GET", "/scene.json").body);
  const nlohmann::json* rcm = nullptr;
  for (const nlohmann::json& camera : scene.at("cameras")) {
    if (!camera.at("name").get<std::string>().ends_with("/rcm_close")) continue;
    ASSERT_EQ(rcm, nullptr) << "two cameras named rcm_close";
    rcm = &camera;
  }
  ASSERT_NE(rcm, nullptr) << "the example world has a camera named rcm_close";

  open(read_only_.url + "/?camera=rcm_close");
  EXPECT_EQ(browser_->evaluate("window.afhub.camera"), rcm->at("name"));
  const nlohmann::json position =
      browser_->evaluate("[camera.position.x, camera.position.y, camera.position.z]");
  ASSERT_EQ(position.size(), 3U) << browser_->problem();
  for (std::size_t i = 0; i < 3; ++i)
    EXPECT_NEAR(position.at(i).get<double>(), rcm->at("position").at(i).get<double>(), 1e-6) << i;
  EXPECT_EQ(text_of("#cameras .current"), "rcm_close [paired: Test Touch]");
  // Paired by its block key "camera_overview" (its name is "overview").
  EXPECT_EQ(text_of("#cameras a[href=\"/?camera=overview\"]"), "overview [paired: Key Touch]");
  EXPECT_EQ(browser_->evaluate("document.querySelectorAll('#cameras .paired').length"), 2);
  EXPECT_EQ(text_of("#message"), "");
  expect_clean_console();

  // Another camera: another pose.
  open(read_only_.url + "/?camera=overview");
  EXPECT_TRUE(contains(string_of(browser_->evaluate("window.afhub.camera")), "overview"));
  EXPECT_GT(std::abs(number_of(browser_->evaluate("camera.position.x")) -
                     rcm->at("position").at(0).get<double>()),
            0.5);

  // An unknown name: said on the page, with the cameras there are.
  open(read_only_.url + "/?camera=nosuch");
  const std::string message = text_of("#message");
  EXPECT_TRUE(contains(message, "No camera named \"nosuch\"")) << message;
  EXPECT_TRUE(contains(message, "overview, rcm_close, flange")) << message;
  expect_clean_console();
}

// The example cloth (examples/models/cloth.yaml, a Bullet soft body) drawn by the
// page: its faces from the scene, its node positions from the frames.
class ViewSoftBodyTest : public ViewPageTest {
 protected:
  static void SetUpTestSuite() {
    ASSERT_NO_FATAL_FAILURE(start_physics("3", "afhub/cloth/cloth"));
    commands_ = start_view({"--allow-commands"});
    browser_ = std::make_unique<Browser>(dir_);
    ASSERT_TRUE(browser_->ready()) << browser_->problem();
  }
  static double centre_z() {
    const nlohmann::json centre = browser_->evaluate("window.afhub.softCentres[0] || []");
    return centre.size() == 3 ? number_of(centre.at(2)) : NAN;
  }
};

TEST_F(ViewSoftBodyTest, TheClothIsDrawnAndItsNodesMoveAsItFalls) {
  const nlohmann::json scene = parse_json(http_request(commands_.port, "GET", "/scene.json").body);
  ASSERT_EQ(scene.at("soft_bodies").size(), 1U);
  const nlohmann::json& cloth = scene.at("soft_bodies").at(0);
  EXPECT_EQ(cloth.at("channel"), "afhub/cloth/cloth");
  EXPECT_EQ(cloth.at("nodes"), 169);                  // 13 x 13
  EXPECT_EQ(cloth.at("faces").size(), 2U * 144 * 3);  // two triangles per cell

  open(commands_.page);
  ASSERT_TRUE(wait_until([] { return browser_->evaluate("window.afhub.softBodies") == 1; },
                         std::chrono::seconds(10)))
      << "the page drew no soft body";
  // Paused and reset, the cloth is back at 1 m; resumed, it falls, and the frames
  // carry its nodes down.
  ASSERT_EQ(run_afhub({"world", "pause"}).exit_code, 0);
  ASSERT_EQ(run_afhub({"world", "reset"}).exit_code, 0);
  ASSERT_TRUE(wait_until([] { return centre_z() > 0.9; }, std::chrono::seconds(5)))
      << "the cloth's nodes did not come back to 1 m: centre z " << centre_z();
  const double start = centre_z();
  ASSERT_EQ(run_afhub({"world", "resume"}).exit_code, 0);
  ASSERT_TRUE(wait_until([] { return centre_z() < 0.3; }, std::chrono::seconds(5)))
      << "the cloth's nodes did not fall: centre z " << centre_z();
  std::printf("cloth centre z in the frames: %.3f, then %.3f\n", start, centre_z());

  // Drawn: the pixels that change when the cloth is hidden, around where it is.
  ASSERT_EQ(run_afhub({"world", "pause"}).exit_code, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const nlohmann::json drawn = browser_->evaluate(R"((() => {
      const mesh = softBodies[0];
      const read = () => {
        renderer.render(world, camera);
        const gl = renderer.getContext();
        const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
        const pixels = new Uint8Array(w * h * 4);
        gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
        return pixels;
      };
      const shown = read();
      mesh.visible = false;
      const hidden = read();
      mesh.visible = true;
      let changed = 0;
      for (let i = 0; i < shown.length; i += 4)
        if (Math.abs(shown[i] - hidden[i]) + Math.abs(shown[i + 1] - hidden[i + 1]) +
            Math.abs(shown[i + 2] - hidden[i + 2]) > 30) changed++;
      return changed;
    })())");
  ASSERT_EQ(run_afhub({"world", "resume"}).exit_code, 0);
  std::printf("cloth: %.0f pixels drawn\n", number_of(drawn));
  EXPECT_GT(number_of(drawn), 300) << "the cloth is not drawn";
  browser_->screenshot(dir_ + "/cloth.png");  // left for a look
  expect_clean_console();
}

// The project's URDF test arm: its link 'fore' has two visual meshes, both a unit
// cube, the first scaled by 0.05, the second by (0.05, 0.05, 0.1) at an <origin>
// (0, 0, 0.2, yaw 0.5).
class ViewUrdfTest : public ViewPageTest {
 protected:
  static void SetUpTestSuite() {
    char pattern[] = "/tmp/afhub_view_urdf_test_XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
    physics_ = std::make_unique<ScopedProcess>(
        spawn_afhub({"run", std::string(AFHUB_URDF_TEST_MODELS) + "/arm.urdf"}, dir_ + "/run.log"));
    connect_to_hub("viewurdftest", HubPolicy::kRequire);
    base_ = std::make_unique<BodyClient>("ambf/env/test_arm/base");
    ASSERT_TRUE(
        wait_until([] { return base_->latest_state() != nullptr; }, std::chrono::seconds(20)))
        << read_file(dir_ + "/run.log");
    read_only_ = start_view({});
    browser_ = std::make_unique<Browser>(dir_);
    ASSERT_TRUE(browser_->ready()) << browser_->problem();
  }
};

TEST_F(ViewUrdfTest, EveryVisualMeshIsDrawnAtItsOriginAndScale) {
  open(read_only_.url + "/");
  ASSERT_TRUE(wait_until([] { return browser_->evaluate("window.afhub.meshesLoaded") == 2; },
                         std::chrono::seconds(10)))
      << "meshes loaded: " << browser_->evaluate("window.afhub.meshesLoaded").dump();
  // Each mesh's box in the link's frame (the link's world matrix taken out for the
  // measure): its centre and its size.
  const nlohmann::json boxes = browser_->evaluate(R"((() => {
      const fore = bodies.find((b) => b.userData.channel === 'ambf/env/test_arm/fore');
      fore.matrixWorld.identity();
      const boxes = fore.children.map((holder) => {
        const box = new THREE.Box3().setFromObject(holder);
        const c = box.getCenter(new THREE.Vector3()), s = box.getSize(new THREE.Vector3());
        return [c.x, c.y, c.z, s.x, s.y, s.z];
      });
      fore.updateMatrixWorld(true);
      return boxes;
    })())");
  ASSERT_TRUE(boxes.is_array() && boxes.size() == 2U) << boxes.dump();
  const double turned_width = 0.05 * (std::cos(0.5) + std::sin(0.5));  // yawed by 0.5 rad
  const double expected[2][6] = {{0, 0, 0, 0.05, 0.05, 0.05},
                                 {0, 0, 0.2, turned_width, turned_width, 0.1}};
  for (int m = 0; m < 2; ++m)
    for (int k = 0; k < 6; ++k)
      EXPECT_NEAR(number_of(boxes.at(m).at(k)), expected[m][k], 1e-4) << boxes.dump();
  expect_clean_console();
}

// AMBF's own world file and input_devices.yaml (../shared/ambf_models): its devices
// pair "camera1", the world file's block key of the camera named "default_camera".
class ViewAmbfPairingTest : public ViewPageTest {
 protected:
  static void SetUpTestSuite() {
    if (!::afhub::testing::shared_models_present()) return;
    char pattern[] = "/tmp/afhub_view_ambf_test_XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
    const std::string descriptions = ::afhub::testing::kSharedModels + "/descriptions";
    physics_ = std::make_unique<ScopedProcess>(
        spawn_afhub({"run", "--world", descriptions + "/world/world.yaml", kModels + "/arm7.yaml"},
                    dir_ + "/run.log"));
    connect_to_hub("viewambftest", HubPolicy::kRequire);
    base_ = std::make_unique<BodyClient>("afhub/arm/base");
    ASSERT_TRUE(
        wait_until([] { return base_->latest_state() != nullptr; }, std::chrono::seconds(20)))
        << read_file(dir_ + "/run.log");
    read_only_ =
        start_view({"--input-devices", descriptions + "/input_devices/input_devices.yaml"});
    browser_ = std::make_unique<Browser>(dir_);
    ASSERT_TRUE(browser_->ready()) << browser_->problem();
  }
};

TEST_F(ViewAmbfPairingTest, ACameraPairedByItsBlockKeyIsMarked) {
  SKIP_WITHOUT_SHARED_MODELS();
  const nlohmann::json scene = parse_json(http_request(read_only_.port, "GET", "/scene.json").body);
  ASSERT_EQ(scene.at("cameras").size(), 1U);
  EXPECT_EQ(scene.at("cameras").at(0).at("key"), "camera1");
  open(read_only_.url + "/");
  const std::string marked = text_of("#cameras a.paired");
  EXPECT_TRUE(marked.starts_with("default_camera [paired: ")) << marked;
  expect_clean_console();
}

}  // namespace
}  // namespace afhub::test
