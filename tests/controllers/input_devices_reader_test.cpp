// AMBF's input device file: the real one in the shared corpus reads with every key
// honoured and no warning; bad files give located errors, unknown keys located
// warnings; `-d` selects devices by index.
#include "afhub/teleop/input_devices_reader.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "afhub/shm_layout/error.hpp"
#include "shared_models.hpp"
#include "text_contains.hpp"

namespace afhub::teleop {
namespace {

namespace fs = std::filesystem;

using afhub::test::contains;

const std::string kRealFile =
    afhub::testing::kSharedModels + "/descriptions/input_devices/input_devices.yaml";

TEST(InputDevicesReader, ReadsAmbfsOwnFile) {
  SKIP_WITHOUT_SHARED_MODELS();
  const InputDevicesFile file = read_input_devices(kRealFile);
  EXPECT_TRUE(file.warnings.empty()) << file.warnings.front();
  ASSERT_EQ(file.devices.size(), 7u);
  const char* order[] = {"MTMR",         "MTML",           "Geomagic Touch", "Razer Hydra0",
                         "Razer Hydra1", "Novint Falcon1", "Novint Falcon2"};
  for (std::size_t i = 0; i < 7; ++i) EXPECT_EQ(file.devices[i].identifier, order[i]);

  const InputDeviceSpec& mtml = file.devices[1];
  EXPECT_EQ(mtml.hardware_name, "MTML");
  EXPECT_DOUBLE_EQ(mtml.haptic_gain_linear, 10.0);
  EXPECT_DOUBLE_EQ(mtml.haptic_gain_angular, 0.0);
  EXPECT_DOUBLE_EQ(mtml.workspace_scale, 5.0);
  EXPECT_TRUE(mtml.location_given);
  EXPECT_DOUBLE_EQ(mtml.location.position_m.x, -0.5);
  EXPECT_EQ(mtml.buttons.clutch, 1);
  EXPECT_EQ(mtml.buttons.camera, 6);
  EXPECT_EQ(mtml.buttons.gripper, -1);  // AMBF's default
  EXPECT_EQ(mtml.buttons.next_mode, 3);
  EXPECT_EQ(mtml.buttons.prev_mode, 4);
  EXPECT_EQ(mtml.pair_cameras, std::vector<std::string>{"camera2"});
  EXPECT_FALSE(mtml.controller_gain.has_value());
  EXPECT_FALSE(mtml.max_force_n.has_value());
  // Resolved against the file's folder, to the PR2 gripper model in the corpus.
  EXPECT_EQ(mtml.simulated_multibody,
            fs::path(afhub::testing::kSharedModels +
                     "/descriptions/multi-bodies/grippers/pr2 gripper small red.yaml")
                .lexically_normal()
                .string());
  EXPECT_TRUE(fs::is_regular_file(mtml.simulated_multibody));
  EXPECT_TRUE(contains(mtml.where, "input_devices.yaml:12:"));

  const InputDeviceSpec& touch = file.devices[2];
  EXPECT_EQ(touch.hardware_name, "PHANTOM Omni");
  EXPECT_DOUBLE_EQ(touch.deadband_n, 0.01);
  EXPECT_DOUBLE_EQ(touch.max_force_n.value_or(-1), 2.0);
  EXPECT_DOUBLE_EQ(touch.max_jerk_n_per_ms.value_or(-1), 0.2);
  EXPECT_DOUBLE_EQ(touch.workspace_scale, 10.0);
  EXPECT_DOUBLE_EQ(touch.location.position_m.y, 0.5);
  EXPECT_EQ(touch.buttons.clutch, 0);
  EXPECT_EQ(touch.buttons.camera, -1);
  EXPECT_EQ(touch.buttons.gripper, 1);
  EXPECT_EQ(touch.buttons.next_mode, 2);

  const InputDeviceSpec& falcon = file.devices[5];
  EXPECT_EQ(falcon.hardware_name, "Falcon");
  EXPECT_DOUBLE_EQ(falcon.haptic_gain_linear, 0.5);
  EXPECT_DOUBLE_EQ(falcon.max_force_n.value_or(-1), 10.0);
  EXPECT_EQ(falcon.buttons.camera, 2);
  EXPECT_EQ(falcon.buttons.prev_mode, 1);
  EXPECT_TRUE(falcon.root_link.empty());
}

TEST(InputDevicesReader, SelectsDevicesByIndexAsAmbfsDashD) {
  SKIP_WITHOUT_SHARED_MODELS();
  const InputDevicesFile file = read_input_devices(kRealFile);
  const std::vector<InputDeviceSpec> chosen = select_devices(file, "5,0");
  ASSERT_EQ(chosen.size(), 2u);
  EXPECT_EQ(chosen[0].identifier, "Novint Falcon1");
  EXPECT_EQ(chosen[1].identifier, "MTMR");
  EXPECT_EQ(select_devices(file, "").size(), 7u);
}

class BadInputDevices : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("afhub_input_devices_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    std::ofstream(dir_ / "gripper.yaml") << "bodies: []\n";
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& text) {
    const std::string path = (dir_ / "devices.yaml").string();
    std::ofstream(path) << text;
    return path;
  }
  // The error of reading `text` ("" if none).
  std::string error_of(const std::string& text) {
    try {
      read_input_devices(write(text));
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  }
  std::string path() const { return (dir_ / "devices.yaml").string(); }

  fs::path dir_;
};

// A valid device, whose line 3 onwards the tests extend.
const std::string kHeader =
    "input devices: [Falcon]\n"
    "Falcon:\n"
    "  hardware name: Falcon\n"
    "  simulated multibody: gripper.yaml\n";

TEST_F(BadInputDevices, AValidSmallFileReadsWithDefaults) {
  const InputDevicesFile file = read_input_devices(write(kHeader));
  ASSERT_EQ(file.devices.size(), 1u);
  const InputDeviceSpec& spec = file.devices[0];
  EXPECT_EQ(spec.simulated_multibody, (dir_ / "gripper.yaml").string());
  EXPECT_DOUBLE_EQ(spec.workspace_scale, 10.0);
  EXPECT_EQ(spec.buttons.clutch, 0);
  EXPECT_EQ(spec.buttons.camera, 1);
  EXPECT_FALSE(spec.location_given);
  EXPECT_TRUE(file.warnings.empty());
}

TEST_F(BadInputDevices, ReadsControllerGainsAndOrientation) {
  const InputDevicesFile file = read_input_devices(
      write(kHeader +
            "  controller gain: {linear: {P: 200, D: 20}, angular: {P: 5, D: 0.5}}\n"
            "  location: {position: {x: 1, y: 2, z: 3}, orientation: {r: 0.1, p: 0.2, y: 0.3}}\n"
            "  orientation offset: {r: 0, p: 0, y: 1.5}\n"
            "  root link: palm\n"
            "  enable joint control: false\n"));
  const InputDeviceSpec& spec = file.devices[0];
  ASSERT_TRUE(spec.controller_gain.has_value());
  EXPECT_DOUBLE_EQ(spec.controller_gain->linear.p, 200);
  EXPECT_DOUBLE_EQ(spec.controller_gain->linear.d, 20);
  EXPECT_DOUBLE_EQ(spec.controller_gain->angular.p, 5);
  EXPECT_DOUBLE_EQ(spec.controller_gain->angular.d, 0.5);
  EXPECT_DOUBLE_EQ(spec.location.position_m.z, 3);
  EXPECT_DOUBLE_EQ(spec.location.rpy_rad.y, 0.2);
  EXPECT_DOUBLE_EQ(spec.orientation_offset_rpy.z, 1.5);
  EXPECT_EQ(spec.root_link, "palm");
  EXPECT_FALSE(spec.enable_joint_control);
}

TEST_F(BadInputDevices, UnknownKeysGiveLocatedWarnings) {
  const InputDevicesFile file = read_input_devices(
      write(kHeader + "  haptic gian: 3\n  button mapping: {a1: 0, clutch: 2}\n"));
  ASSERT_EQ(file.warnings.size(), 2u);
  EXPECT_EQ(file.warnings[0], path() +
                                  ":5:3: warning: unknown key 'haptic gian' in the device "
                                  "'Falcon' is ignored");
  EXPECT_TRUE(contains(file.warnings[1], path() + ":6:27: warning: unknown key 'clutch'"))
      << file.warnings[1];
}

TEST_F(BadInputDevices, BadValuesGiveLocatedErrors) {
  struct Case {
    std::string lines;
    std::string where;
    std::string what;
  };
  const Case cases[] = {
      {"  workspace scaling: -2\n", ":5:22:", "'workspace scaling' must be positive"},
      {"  workspace scaling: lots\n", ":5:22:", "must be a number, got 'lots'"},
      {"  haptic gain: [1, 2]\n", ":5:16:", "'haptic gain' must be a map"},
      {"  haptic gain: {linear: -1}\n", ":5:25:", "'haptic gain.linear' must not be negative"},
      {"  max force: 0\n", ":5:14:", "'max force' must be positive"},
      {"  max force: .nan\n", ":5:14:", "must be finite"},
      {"  deadband: 1e300\n", ":5:13:", "beyond any physical value"},
      {"  button mapping: {a1: 1.5}\n", ":5:24:", "must be a button index"},
      {"  button mapping: {a2: 40}\n", ":5:24:", "a button index is 0 to 31"},
      {"  location: {position: {x: 1, y: 2}}\n", ":5:24:", "'location.position' is missing 'z'"},
      {"  pair cameras: camera1\n", ":5:17:", "'pair cameras' must be a list"},
      {"  controller gain: {linear: {P: -5}}\n",
       ":5:33:", "'controller gain.linear.P' must not be negative"},
      {"  enable joint control: maybe\n", ":5:25:", "must be true or false"},
      {"  hardware name: Other\n", ":5:3:", "'hardware name' is written twice"},
  };
  for (const Case& c : cases) {
    const std::string error = error_of(kHeader + c.lines);
    EXPECT_TRUE(contains(error, path() + c.where + " error: ") && contains(error, c.what))
        << "for " << c.lines << "got: " << error;
  }
}

TEST_F(BadInputDevices, BadStructureGivesLocatedErrors) {
  EXPECT_TRUE(contains(error_of("input devices: [Falcon, Omni]\nFalcon:\n  hardware name: F\n"
                                "  root link: palm\n"),
                       path() + ":1:25: error: 'Omni' is listed in 'input devices' but the "
                                "file has no top-level 'Omni' block"));
  EXPECT_TRUE(contains(error_of("input devices: [Falcon]\nFalcon:\n  root link: palm\n"),
                       path() + ":1:17: error: the device 'Falcon' has no 'hardware name'"));
  EXPECT_TRUE(contains(error_of("input devices: [Falcon]\nFalcon:\n  hardware name: F\n"),
                       path() + ":1:17: error: the device 'Falcon' has neither 'simulated "
                                "multibody' nor 'root link'"));
  EXPECT_TRUE(
      contains(error_of("devices: [Falcon]\n"), path() + ":1:1: error: no 'input devices' list"));
  EXPECT_TRUE(contains(error_of("input devices: Falcon\n"),
                       path() + ":1:16: error: 'input devices' must be a list"));
  EXPECT_TRUE(contains(error_of("input devices: [Falcon\n"), path() + ":"));
  EXPECT_TRUE(contains(error_of(""), path() + ":1:1: error: the file holds nothing"));
  EXPECT_TRUE(contains(error_of("input devices: [Falcon, Falcon]\nFalcon:\n  hardware name: F\n"
                                "  root link: palm\n"),
                       path() + ":1:25: error: 'Falcon' is listed twice"));
}

TEST_F(BadInputDevices, AMissingFileOrDirectoryIsNamed) {
  const std::string missing = (dir_ / "nope.yaml").string();
  try {
    read_input_devices(missing);
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_EQ(std::string(error.what()),
              missing +
                  ": error: no such file; expected an input device file (input_devices.yaml: a "
                  "map with an 'input devices' list)");
  }
  EXPECT_THROW(read_input_devices(dir_.string()), Error);
}

TEST_F(BadInputDevices, SelectionErrorsListTheDevices) {
  const InputDevicesFile file = read_input_devices(write(kHeader));
  auto error_of_selection = [&](const std::string& selection) -> std::string {
    try {
      select_devices(file, selection);
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  };
  EXPECT_EQ(error_of_selection("0"), "");
  EXPECT_TRUE(contains(error_of_selection("3"),
                       "-d 3: there is no device 3 in " + path() + " (devices: 0 'Falcon')"));
  EXPECT_TRUE(contains(error_of_selection("a"), "-d a: 'a' is not a device index"));
  EXPECT_TRUE(contains(error_of_selection("-1"), "'-1' is not a device index"));
  EXPECT_TRUE(contains(error_of_selection("0,"), "ends with ','"));
  EXPECT_TRUE(contains(error_of_selection("0,0"), "selected twice"));
  // The selected device's model must exist; the error points at its key.
  fs::remove(dir_ / "gripper.yaml");
  EXPECT_TRUE(contains(error_of_selection("0"),
                       path() + ":4:24: error: the simulated multibody of 'Falcon' is " +
                           (dir_ / "gripper.yaml").string() + ", and there is no such file"));
}

}  // namespace
}  // namespace afhub::teleop
