// Bad model files get a located error ("file:line:col: error: ..."), never a crash
// or a hang (issue 13): broken and unreadable meshes and model files, loading
// linear in the bodies, the hub's limits and every per-body capacity, duplicate
// and reserved names, and physically absurd values.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/mesh.hpp"
#include "afhub/physics/scene_loader.hpp"
#include "afhub/physics/simulation.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "model_files.hpp"
#include "text_contains.hpp"

namespace afhub::physics {
namespace {

namespace fs = std::filesystem;

using afhub::test::contains;

// The error of loading `files` and building their simulation ("" if none).
std::string error_of(const std::vector<std::string>& files, bool build = true) {
  try {
    Model model = load_adf_files(files);
    check_meshes(model);
    if (build) Simulation sim(model, 0.001);
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

// Runs `body` in a child process as an unprivileged user, so that file modes
// apply (the tests may run as root); returns the child's exit code.
int as_unprivileged_user(const std::function<int()>& body) {
  const pid_t child = ::fork();
  if (child == 0) {
    if (::geteuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0)) ::_exit(90);
    ::_exit(body());
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

class BadInput : public ::testing::Test {
 protected:
  // A body with `mesh` as its mesh, in model.yaml beside it.
  std::string model_with_mesh(const std::string& mesh) {
    return folder_.write("model.yaml",
                         "bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n  mesh: " + mesh + "\n");
  }
  std::string write_bytes(const std::string& name, const std::string& bytes) {
    const fs::path path = folder_.dir() / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path.string();
  }
  testing::ModelFolder folder_;
};

// A binary STL: 80-byte header, a triangle count, then 50 bytes per triangle.
std::string binary_stl(std::uint32_t claimed, const std::vector<std::array<float, 9>>& triangles) {
  std::string bytes(80, ' ');
  bytes.append(reinterpret_cast<const char*>(&claimed), 4);
  for (const auto& t : triangles) {
    const float normal[3] = {0, 0, 1};
    bytes.append(reinterpret_cast<const char*>(normal), 12);
    bytes.append(reinterpret_cast<const char*>(t.data()), 36);
    bytes.append(2, '\0');
  }
  return bytes;
}

TEST_F(BadInput, ABrokenMeshIsALocatedErrorNotACrash) {
  const float nan = std::nanf("");
  struct Case {
    std::string name, bytes, expected;
  };
  const std::vector<Case> cases = {
      {"empty.STL", "", "cannot read this mesh"},
      {"garbage.STL", std::string(300, 'x') + "\nnot a mesh at all\n", "cannot read this mesh"},
      {"claims.STL", binary_stl(0xFFFFFFFFu, {{0, 0, 0, 1, 0, 0, 0, 1, 0}}),
       "cannot read this mesh"},
      {"nan.STL", binary_stl(1, {{0, 0, 0, nan, 0, 0, 0, 1, 0}}), "not a finite point"},
  };
  for (const Case& c : cases) {
    write_bytes(c.name, c.bytes);
    const std::string model = model_with_mesh(c.name);
    for (bool build : {false, true}) {
      const std::string message = error_of({model}, build);
      EXPECT_TRUE(
          contains(message, "model.yaml:3:3: error: body 'BODY a': its mesh cannot be used"))
          << c.name << ": " << message;
      EXPECT_TRUE(contains(message, c.name)) << message;
      EXPECT_TRUE(contains(message, c.expected)) << c.name << ": " << message;
    }
  }
}

TEST_F(BadInput, AMeshLargerThanTheBoundIsRefusedBeforeItIsRead) {
  // Sparse: 1 GB on paper, nothing on disk.
  const std::string mesh = write_bytes("huge.STL", "");
  fs::resize_file(mesh, std::uintmax_t{1} << 30);
  const std::string message = error_of({model_with_mesh("huge.STL")});
  EXPECT_TRUE(contains(message, "model.yaml:3:3: error: body 'BODY a'")) << message;
  EXPECT_TRUE(contains(message, "the file is 1024 MB, larger than the 256 MB")) << message;
}

TEST_F(BadInput, AnUnreadableMeshOrModelSaysPermissionDenied) {
  const std::string mesh = write_bytes("locked.STL", binary_stl(1, {{0, 0, 0, 1, 0, 0, 0, 1, 0}}));
  const std::string model = model_with_mesh("locked.STL");
  const std::string locked_model = folder_.write("locked.yaml", "bodies: []\n");
  fs::permissions(mesh, fs::perms::none);
  fs::permissions(locked_model, fs::perms::none);
  fs::permissions(folder_.dir(), fs::perms::all);
  const int code = as_unprivileged_user([&] {
    const std::string message = error_of({model}, false);
    if (!contains(message, "model.yaml:3:3: error: body 'BODY a'") ||
        !contains(message, "locked.STL: error: permission denied"))
      return 1;
    if (!contains(error_of({locked_model}), "locked.yaml: error: permission denied")) return 2;
    return 0;
  });
  EXPECT_EQ(code, 0) << "1: the mesh, 2: the model file were not refused as unreadable";
}

TEST_F(BadInput, AMeshNameTooLongForTheFileSystemSaysSo) {
  const std::string name = std::string(300, 'm') + ".STL";
  const std::string message = error_of({model_with_mesh(name)}, false);
  EXPECT_TRUE(contains(message, "model.yaml:5:9: error: mesh '" + name + "' is not a readable"))
      << message;
  EXPECT_TRUE(contains(message, "(is a name too long for the file system)")) << message;
  SceneRequest request;
  request.world_file = folder_.write("world.yaml", "environment: " + name + "\n");
  request.adf_files = {model_with_mesh("")};
  try {
    load_scene(request);
    ADD_FAILURE() << "loaded a world whose environment cannot exist";
  } catch (const Error& error) {
    EXPECT_TRUE(contains(error.what(), "world.yaml:1:14: error: environment")) << error.what();
  }
}

// A mesh path that is not a file says what it is, not "not found".
TEST_F(BadInput, AMeshThatIsADirectoryAFifoADeviceOrASymlinkLoopSaysWhatItIs) {
  fs::create_directory(folder_.dir() / "folder.STL");
  ASSERT_EQ(mkfifo((folder_.dir() / "pipe.STL").c_str(), 0600), 0);
  fs::create_symlink("loop-b.STL", folder_.dir() / "loop-a.STL");
  fs::create_symlink("loop-a.STL", folder_.dir() / "loop-b.STL");
  fs::create_symlink("gone.STL", folder_.dir() / "dangling.STL");
  const struct {
    std::string mesh, expected;
  } cases[] = {
      {"folder.STL", "(is a directory)"},
      {"pipe.STL", "(is a FIFO)"},
      {"/dev/zero", "/dev/zero (is a character device)"},
      {"loop-a.STL", "(is a symlink loop)"},
      {"dangling.STL", "(is a broken symlink to 'gone.STL')"},
      {"nothere.STL", "(does not exist)"},
  };
  for (const auto& c : cases) {
    const std::string message = error_of({model_with_mesh(c.mesh)}, false);
    EXPECT_TRUE(contains(message, "model.yaml:5:9: error: mesh '" + c.mesh + "' is not a readable"))
        << message;
    EXPECT_TRUE(contains(message, c.expected)) << c.mesh << ": " << message;
  }
}

TEST_F(BadInput, ADirectoryGivenAsAModelSaysSo) {
  const std::string message = error_of({folder_.dir().string()});
  EXPECT_TRUE(contains(message, "this is a directory; expected an ADF file")) << message;
}

// A launch or a world file given as a model loaded nothing: `afhub run` ran an empty
// world and `afhub check` said it was fine.
TEST_F(BadInput, ALaunchOrWorldFileGivenAsAModelSaysHowToGiveIt) {
  const std::string launch = folder_.write("launch.yaml", "multibody configs: [./arm.yaml]\n");
  const std::string world = folder_.write("world.yaml", "lights: []\ncameras: []\n");
  const std::string launch_message = error_of({launch});
  EXPECT_TRUE(contains(launch_message, launch + ":1:1: error: this is a launch file"))
      << launch_message;
  EXPECT_TRUE(contains(launch_message, "--launch " + launch + " -l 0,1")) << launch_message;
  const std::string world_message = error_of({world});
  EXPECT_TRUE(contains(world_message, "this is a world file")) << world_message;
  EXPECT_TRUE(contains(world_message, "--world " + world)) << world_message;
}

// The fastest of three; with `build`, the simulation is built too.
double cpu_seconds_to_load(const std::string& path, bool build = false) {
  double best = 1e9;
  for (int round = 0; round < 3; ++round) {
    const std::clock_t start = std::clock();
    const Model model = load_adf_files({path});
    if (build) Simulation sim(model, 0.001);
    best = std::min(best, static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC);
  }
  return best;
}

// Growth as a ratio of the process's CPU time (not wall clock), the fastest of
// three: 8 times the bodies must cost about 8 times as much. Loading used to be
// quadratic (over 30 times here); the bound leaves room for noise.
TEST_F(BadInput, LoadingIsLinearInTheBodies) {
  const std::string small = folder_.write("small.yaml", testing::passive_spheres_at_origin(2000));
  const std::string large = folder_.write("large.yaml", testing::passive_spheres_at_origin(16000));
  const double ratio = cpu_seconds_to_load(large) / cpu_seconds_to_load(small);
  EXPECT_LT(ratio, 16.0) << "8x the bodies took " << ratio << "x the CPU time";
  std::printf("8x the bodies took %.1fx the CPU time\n", ratio);
}

// Every body is at the origin: each pair overlaps. Bullet's broadphase
// met each added body's overlaps at once, which made building cubic (over 50 times
// the CPU time here); now the first step meets them.
TEST_F(BadInput, BuildingIsLinearInBodiesThatAllOverlap) {
  const std::string small = folder_.write("small.yaml", testing::passive_spheres_at_origin(500));
  const std::string large = folder_.write("large.yaml", testing::passive_spheres_at_origin(2000));
  const double ratio = cpu_seconds_to_load(large, true) / cpu_seconds_to_load(small, true);
  EXPECT_LT(ratio, 8.0) << "4x the bodies took " << ratio << "x the CPU time";
  std::printf("4x the overlapping bodies took %.1fx the CPU time to build\n", ratio);
}

TEST_F(BadInput, MoreBodiesThanASimulationHoldsAreRefusedBeforeAnyIsRead) {
  const std::string text =
      testing::passive_spheres_at_origin(static_cast<int>(kMaxModelBodies) + 1);
  const std::string message = error_of({folder_.write("many.yaml", text)}, false);
  EXPECT_TRUE(contains(message, "many.yaml:1:10: error: the model lists " +
                                    std::to_string(kMaxModelBodies + 1) +
                                    " bodies with this list; afhub simulates at most " +
                                    std::to_string(kMaxModelBodies) + " (kMaxModelBodies)"))
      << message;
  // Two files of half as many each: the second list passes the bound.
  const std::string half =
      testing::passive_spheres_at_origin(static_cast<int>(kMaxModelBodies / 2) + 1);
  const std::string first = folder_.write("first.yaml", half);
  std::string renamed = half;
  for (std::size_t at = 0; (at = renamed.find(" b", at)) != std::string::npos; at += 3)
    renamed.replace(at, 2, " c");
  const std::string second = folder_.write("second.yaml", renamed);
  EXPECT_TRUE(
      contains(error_of({first, second}, false), "second.yaml:1:10: error: the model lists"));
}

TEST_F(BadInput, MoreBodiesThanTheHubHoldsAreRefusedAtOnce) {
  std::string text = testing::passive_spheres_at_origin(kMaxBodies + 50);
  // Passive bodies publish nothing: any number of them load.
  EXPECT_EQ(error_of({folder_.write("passive.yaml", text)}, false), "");
  std::string active;
  for (std::size_t at = 0; (at = text.find("  passive: true\n")) != std::string::npos;)
    text.erase(at, 16);
  const std::string message = error_of({folder_.write("active.yaml", text)}, false);
  EXPECT_TRUE(contains(message, "active.yaml:"));
  EXPECT_TRUE(contains(message, "'BODY b" + std::to_string(kMaxBodies) +
                                    "' is published body number " + std::to_string(kMaxBodies + 1) +
                                    "; the hub holds at most " + std::to_string(kMaxBodies)))
      << message;
}

std::string body(const std::string& id, const std::string& extra = "") {
  return "BODY " + id + ":\n  name: " + id + "\n  mass: 1\n" + extra;
}

TEST_F(BadInput, DuplicateAndReservedNamesAreRefusedWithBothLocations) {
  struct Case {
    std::string text, expected;
  };
  const std::string joint =
      "  parent pivot: {x: 0, y: 0, z: 0}\n  child pivot: {x: 0, y: 0, z: 0}\n"
      "  parent axis: {x: 0, y: 0, z: 1}\n  child axis: {x: 0, y: 0, z: 1}\n  type: revolute\n";
  const std::vector<Case> cases = {
      {"bodies: [BODY a, BODY b]\n" + body("a") + "BODY b:\n  name: a\n  mass: 1\n",
       "model.yaml:6:3: error: body channel 'ambf/env/a' is already used by the body at "},
      {"namespace: /\nbodies: [BODY world]\n" + body("world"),
       "model.yaml:4:3: error: a body on channel 'world' would collide with the hub's 'world'"},
      {"bodies: [BODY a, BODY b, BODY c]\njoints: [JOINT j, JOINT k]\n" + body("a") + body("b") +
           body("c") + "JOINT j:\n  name: j\n  parent: BODY a\n  child: BODY b\n" + joint +
           "JOINT k:\n  name: j\n  parent: BODY b\n  child: BODY c\n" + joint,
       "error: joint channel 'ambf/env/j' is already used by the joint at "},
      {"bodies: [BODY a]\n" + body("a") + "BODY a:\n  name: b\n  mass: 1\n",
       "model.yaml:5:1: error: 'BODY a' is written twice in this map (first at "},
  };
  for (const Case& c : cases) {
    const std::string message = error_of({folder_.write("model.yaml", c.text)}, false);
    EXPECT_TRUE(contains(message, c.expected)) << c.text << "\n" << message;
    if (contains(c.expected, "already used") || contains(c.expected, "twice")) {
      EXPECT_NE(message.find("model.yaml:"), message.rfind("model.yaml:"))
          << "both locations: " << message;
    }
  }
}

TEST_F(BadInput, AbsurdValuesAreRefusedWithTheirLocation) {
  const std::string head = "bodies: [BODY a]\nBODY a:\n  name: a\n";
  struct Case {
    std::string body, expected;
  };
  const std::vector<Case> cases = {
      {"  mass: 1e308\n", "model.yaml:4:9: error: 'mass' is 1e308, beyond"},
      {"  mass: 1e7\n", "model.yaml:4:9: error: 'mass' is 1e7 kg, beyond the bound of 1e+06 kg"},
      {"  mass: .nan\n", "model.yaml:4:9: error: 'mass' must be finite"},
      // Taken, it blew the arm apart (a joint error of 1 km) with no warning.
      {"  mass: 1e-300\n",
       "model.yaml:4:9: error: 'mass' is 1e-300 kg, below the 1e-09 kg a moving body needs"},
      {"  mass: 1\n  location: {position: {x: 1e308, y: 0, z: 0}}\n",
       "model.yaml:5:28: error: 'location.position.x' is 1e308, beyond"},
      {"  mass: 1\n  location: {position: {x: 1e6, y: 0, z: 0}}\n",
       "model.yaml:5:24: error: 'location.position' has a component of 1e+06 m, beyond the bound"},
      {"  mass: 1\n  shape: sphere\n  geometry: {radius: 1e308}\n",
       "model.yaml:6:22: error: 'geometry.radius' is 1e308, beyond"},
      {"  mass: 1\n  shape: box\n  geometry: {x: 1, y: 1e6, z: 1}\n",
       "model.yaml:6:23: error: 'geometry.y' is 1e6, beyond the bound of 100000 m"},
      {"  mass: 1\n  scale: 1e308\n", "model.yaml:5:10: error: 'scale' is 1e308, beyond"},
      {"  mass: 1\n  scale: 1e4\n", "model.yaml:5:10: error: 'scale' is 1e4, beyond the bound"},
      {"  mass: 1\n  inertia: {ix: 1e308, iy: 1, iz: 1}\n",
       "model.yaml:5:17: error: 'inertia.ix' is 1e308, beyond"},
      {"  mass: 1\n  controller: {linear: {P: 1e308}}\n",
       "model.yaml:5:28: error: 'controller.linear.P' is 1e308, beyond"},
      {"  mass: 1\n  visual meshes: part.stl\n",
       "model.yaml:5:18: error: 'visual meshes' must be a non-empty list of {mesh: FILE"},
      {"  mass: 1\n  collision meshes: [{offset: {position: {x: 1, y: 0, z: 0}}}]\n",
       "model.yaml:5:22: error: 'collision meshes' entry needs 'mesh'"},
      {"  mass: 1\n  visual meshes: [{mesh: part.stl, scale: {x: 1, y: 0, z: 1}}]\n",
       "error: each axis of a 'visual meshes' scale must be other than 0 and within -1000 to "
       "1000 (negative: mirrored)"},
  };
  folder_.write("part.stl", "solid part\nendsolid part\n");
  for (const Case& c : cases) {
    const std::string message = error_of({folder_.write("model.yaml", head + c.body)}, false);
    EXPECT_TRUE(contains(message, c.expected)) << c.body << "\n" << message;
  }
  // Merely large values within the bounds load.
  EXPECT_EQ(
      error_of({folder_.write("model.yaml", head + "  mass: 1e5\n  shape: sphere\n  geometry: "
                                                   "{radius: 1e3}\n  controller: {linear: {P: "
                                                   "1e8}}\n")},
               false),
      "");
}

TEST_F(BadInput, EveryPerBodyCapacityIsEnforcedWithItsLocation) {
  std::string actuators = "bodies: [BODY a]\n" + body("a") + "actuators: [";
  for (int i = 0; i < 9; ++i) actuators += (i ? ", ACTUATOR " : "ACTUATOR ") + std::to_string(i);
  actuators += "]\n";
  for (int i = 0; i < 9; ++i)
    actuators += "ACTUATOR " + std::to_string(i) + ":\n  name: c" + std::to_string(i) +
                 "\n  type: Constraint\n  parent: BODY a\n";
  std::string message = error_of({folder_.write("actuators.yaml", actuators)}, false);
  EXPECT_TRUE(contains(message,
                       "actuators.yaml:39:3: error: body 'BODY a' has more than 8 "
                       "actuators"))
      << message;

  const std::string ray = "{offset: {x: 0, y: 0, z: 0}, direction: {x: 1, y: 0, z: 0}}";
  std::string rays = "[" + ray;
  for (int i = 1; i < 20; ++i) rays += ", " + ray;
  rays += "]";
  const std::string sensors =
      "bodies: [BODY a]\n" + body("a") + "sensors: [SENSOR s, SENSOR t]\n" +
      "SENSOR s:\n  name: s\n  type: Proximity\n  parent: BODY a\n  array: " + rays + "\n" +
      "SENSOR t:\n  name: t\n  type: Proximity\n  parent: BODY a\n  array: " + rays + "\n";
  message = error_of({folder_.write("sensors.yaml", sensors)}, false);
  EXPECT_TRUE(contains(message,
                       "sensors.yaml:12:3: error: the sensors on body 'BODY a' have 40 "
                       "rays with this one; a body's state carries at most 32"))
      << message;

  const std::string parametric =
      "bodies: [BODY a]\n" + body("a") + "sensors: [SENSOR s]\n" +
      "SENSOR s:\n  name: s\n  type: Proximity\n  parent: BODY a\n"
      "  parametric: {resolution: 1e9, horizontal angle: 1, vertical angle: 1}\n";
  message = error_of({folder_.write("parametric.yaml", parametric)}, false);
  EXPECT_TRUE(contains(message, "parametric.yaml:10:28: error: 'parametric.resolution' must be"))
      << message;

  const int links = static_cast<int>(kMaxJointsPerBody) + 1;
  std::string chain = "bodies: [BODY b0";
  for (int i = 1; i <= links; ++i) chain += ", BODY b" + std::to_string(i);
  chain += "]\njoints: [JOINT j1";
  for (int i = 2; i <= links; ++i) chain += ", JOINT j" + std::to_string(i);
  chain += "]\n";
  // The links publish nothing (passive): the joints below the root are what is counted.
  chain += body("b0");
  for (int i = 1; i <= links; ++i) chain += body("b" + std::to_string(i)) + "  passive: true\n";
  for (int i = 1; i <= links; ++i)
    chain += "JOINT j" + std::to_string(i) + ":\n  name: j" + std::to_string(i) +
             "\n  parent: BODY b" + std::to_string(i - 1) + "\n  child: BODY b" +
             std::to_string(i) +
             "\n  parent pivot: {x: 0, y: 0, z: 0}\n  child pivot: {x: 0, y: 0, z: 0}\n"
             "  parent axis: {x: 0, y: 0, z: 1}\n  child axis: {x: 0, y: 0, z: 1}\n"
             "  type: revolute\n";
  message = error_of({folder_.write("chain.yaml", chain)}, false);
  EXPECT_TRUE(contains(message, "chain.yaml:4:3: error: body 'BODY b0' has " +
                                    std::to_string(links) + " joints below it"))
      << message;

  std::string world = "lights: [";
  for (int i = 0; i < 9; ++i) world += (i ? ", LIGHT " : "LIGHT ") + std::to_string(i);
  world += "]\n";
  for (int i = 0; i < 9; ++i) world += "LIGHT " + std::to_string(i) + ":\n  name: l\n";
  SceneRequest request;
  request.world_file = folder_.write("world.yaml", world);
  request.adf_files = {folder_.write("one.yaml", "bodies: [BODY a]\n" + body("a"))};
  message.clear();
  try {
    load_scene(request);
  } catch (const Error& error) {
    message = error.what();
  }
  EXPECT_TRUE(contains(message, "world.yaml:1:82: error: more than 8 lights")) << message;

  const std::string long_name = std::string(64, 'j');
  message = error_of(
      {folder_.write("long.yaml", "bodies: [BODY a, BODY b]\njoints: [JOINT j]\n" + body("a") +
                                      body("b") + "JOINT j:\n  name: " + long_name +
                                      "\n  parent: BODY a\n  child: BODY b\n"
                                      "  parent pivot: {x: 0, y: 0, z: 0}\n"
                                      "  child pivot: {x: 0, y: 0, z: 0}\n"
                                      "  parent axis: {x: 0, y: 0, z: 1}\n"
                                      "  child axis: {x: 0, y: 0, z: 1}\n"
                                      "  type: revolute\n")},
      false);
  EXPECT_TRUE(contains(message, "long.yaml:10:3: error: joint name '" + long_name + "' has 64"))
      << message;
}

// A world file's cameras and lists, and a model or launch file given as the world
// (each was taken silently: a camera with no view, a light twice, no bodies loaded).
TEST_F(BadInput, AWorldFilesCamerasListsAndKeysAreChecked) {
  const auto scene_with = [&](const std::string& world) {
    SceneRequest request;
    request.world_file = folder_.write("world.yaml", world);
    request.adf_files = {folder_.write("one.yaml", "bodies: [BODY a]\n" + body("a"))};
    return request;
  };
  const auto error_of_world = [&](const std::string& world) -> std::string {
    try {
      load_scene(scene_with(world));
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  };
  const std::string camera = "cameras: [c]\nc:\n  location: {x: 1, y: 2, z: 3}\n";
  EXPECT_TRUE(contains(error_of_world(camera + "  look at: {x: 1, y: 2, z: 3}\n"),
                       "world.yaml:4:12: error: camera 'c' looks at its own location"))
      << error_of_world(camera + "  look at: {x: 1, y: 2, z: 3}\n");
  const std::string along = camera + "  look at: {x: 1, y: 2, z: 0}\n  up: {x: 0, y: 0, z: 1}\n";
  EXPECT_TRUE(contains(error_of_world(along), "world.yaml:5:7: error: camera 'c': 'up' is along"))
      << error_of_world(along);
  const std::string twice = "lights: [l, l]\nl:\n  name: key\n";
  EXPECT_TRUE(contains(error_of_world(twice), "world.yaml:1:13: error: 'l' is listed twice in"))
      << error_of_world(twice);
  // Looking down with an up across the view loads.
  EXPECT_EQ(error_of_world(camera + "  look at: {x: 1, y: 2, z: 0}\n  up: {x: 1, y: 0, z: 0}\n"),
            "");

  const Model model =
      load_scene(scene_with("bodies: [BODY b]\n" + body("b") + "world config: w.yaml\n"));
  ASSERT_EQ(model.warnings.size(), 2u);
  EXPECT_TRUE(contains(model.warnings[0], "world.yaml:1:9: warning: 'bodies' is a model file's"))
      << model.warnings[0];
  EXPECT_TRUE(contains(model.warnings[1], "world.yaml:5:15: warning: 'world config' is a launch"))
      << model.warnings[1];

  // A camera whose parent is not loaded stays in the world frame: said; one whose parent
  // is loaded, not.
  const std::string look = camera + "  look at: {x: 0, y: 0, z: 0}\n";
  const Model unparented = load_scene(scene_with(look + "  parent: /ambf/env/BODY nothere\n"));
  ASSERT_EQ(unparented.warnings.size(), 1u);
  EXPECT_TRUE(contains(unparented.warnings[0],
                       "world.yaml:5:11: warning: 'c' has the parent '/ambf/env/BODY nothere', "
                       "which names no body loaded"))
      << unparented.warnings[0];
  EXPECT_TRUE(load_scene(scene_with(look + "  parent: /ambf/env/BODY a\n")).warnings.empty());
}

}  // namespace
}  // namespace afhub::physics
