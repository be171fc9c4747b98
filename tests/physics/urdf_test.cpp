// URDF robots (physics/urdf_loader.hpp), checked against an independent reference:
// Orocos KDL reads the same files, and every link's pose must match its forward
// kinematics, at load (zero configuration) and at random commanded configurations
// (at the joint positions the simulation reports). Plus what each URDF feature means,
// and a clear error, never a crash, for every bad file.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <kdl/treefksolverpos_recursive.hpp>
#include <kdl_parser/kdl_parser.hpp>
#include <map>
#include <random>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/adf_writer.hpp"
#include "afhub/physics/mesh.hpp"
#include "afhub/physics/mesh_fallback.hpp"
#include "afhub/physics/scene_loader.hpp"
#include "afhub/physics/simulation.hpp"
#include "afhub/physics/urdf_loader.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub::physics {
namespace {

namespace fs = std::filesystem;

const std::string kModels = AFHUB_URDF_TEST_MODELS;
const std::string kShared = AFHUB_SHARED_URDF_MODELS;

std::string shared_urdf(const std::string& relative) {
  return kShared + "/example-robot-data/robots/" + relative;
}

// Through the same entry point `afhub run` uses for model files.
Model load(const std::string& path, const UrdfOptions& options = {}) {
  Model model;
  load_adf_files_into({path}, model, options);
  return model;
}

// A model file (URDF, ADF, launch) written to a temporary file, removed when the test ends.
struct WrittenFile {
  WrittenFile(const std::string& name, const std::string& text)
      : path((fs::temp_directory_path() / ("afhub_urdf_test_" + name)).string()) {
    std::ofstream(path) << text;
  }
  ~WrittenFile() { fs::remove(path); }
  WrittenFile(const WrittenFile&) = delete;
  WrittenFile& operator=(const WrittenFile&) = delete;
  const std::string path;
};

std::string load_error(const std::string& path, const UrdfOptions& options = {}) {
  try {
    load(path, options);
  } catch (const Error& error) {
    return error.what();
  }
  return "(loaded)";
}

// The link frames KDL computes for joint values `q` by joint name; the root is the
// identity.
std::map<std::string, KDL::Frame> kdl_poses(const KDL::Tree& tree,
                                            const std::map<std::string, double>& q) {
  // At least one entry: KDL's solver reads entry 0 for a tree of fixed joints too.
  KDL::JntArray values(std::max(1u, tree.getNrOfJoints()));
  for (const auto& [name, element] : tree.getSegments()) {
    const KDL::Joint& joint = GetTreeElementSegment(element).getJoint();
    if (joint.getType() == KDL::Joint::None) continue;
    auto found = q.find(joint.getName());
    values(GetTreeElementQNr(element)) = found == q.end() ? 0.0 : found->second;
  }
  KDL::TreeFkSolverPos_recursive solver(tree);
  std::map<std::string, KDL::Frame> poses;
  for (const auto& [name, element] : tree.getSegments()) {
    KDL::Frame frame;
    if (solver.JntToCart(values, frame, name) < 0) ADD_FAILURE() << "KDL FK failed for " << name;
    poses[name] = frame;
  }
  return poses;
}

KDL::Rotation to_kdl(const Quaternion& q) {
  return KDL::Rotation::Quaternion(q.x, q.y, q.z, q.w);
}

// The angle of the turn between two rotations, from the sine of its half (acos of a
// dot product would lose the last eight digits).
double angle_between(const KDL::Rotation& a, const KDL::Rotation& b) {
  double x, y, z, w;
  (a.Inverse() * b).GetQuaternion(x, y, z, w);
  return 2.0 * std::atan2(std::sqrt(x * x + y * y + z * z), std::abs(w));
}

// Largest position (m) and rotation (rad) difference of any link against KDL.
struct PoseError {
  double position_m = 0.0, rotation_rad = 0.0;
  std::string worst;
};

PoseError compare(const Simulation& sim, const std::map<std::string, KDL::Frame>& kdl) {
  PoseError error;
  const Model& model = sim.model();
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const std::string link = model.bodies[b].identifier.substr(5);  // "BODY <link>"
    auto found = kdl.find(link);
    if (found == kdl.end()) {
      ADD_FAILURE() << "KDL has no segment " << link;
      continue;
    }
    const Pose pose = sim.body_pose(b);
    const KDL::Frame& f = found->second;
    const double dp = std::hypot(pose.position_m.x - f.p.x(), pose.position_m.y - f.p.y(),
                                 pose.position_m.z - f.p.z());
    const double dr = angle_between(f.M, to_kdl(pose.orientation));
    if (dp > error.position_m || dr > error.rotation_rad) error.worst = link;
    error.position_m = std::max(error.position_m, dp);
    error.rotation_rad = std::max(error.rotation_rad, dr);
  }
  return error;
}

KDL::Tree kdl_tree(const std::string& path) {
  KDL::Tree tree;
  EXPECT_TRUE(kdl_parser::treeFromFile(path, tree)) << path;
  return tree;
}

struct Case {
  std::string path;
  UrdfOptions options;
};

std::vector<Case> valid_cases() {
  std::vector<Case> cases = {{kModels + "/arm.urdf", {}},
                             {kModels + "/gripper_mimic.urdf", {}},
                             {kModels + "/floating_planar.urdf", {{}, true}}};
  if (fs::exists(kShared)) {
    cases.push_back({shared_urdf("ur_description/urdf/ur5_robot.urdf"), {{kShared}, false}});
    cases.push_back(
        {shared_urdf("allegro_hand_description/urdf/allegro_right_hand.urdf"), {{kShared}, false}});
  } else {
    std::printf("urdf_test: %s is absent: the UR5 and the Allegro hand are skipped\n",
                kShared.c_str());
  }
  return cases;
}

TEST(Urdf, EveryLinkAtZeroMatchesKdlWithin1e9) {
  for (const Case& c : valid_cases()) {
    if (c.options.floating_base) continue;  // KDL reads floating and planar joints as fixed
    SCOPED_TRACE(c.path);
    const Model model = load(c.path, c.options);
    const Simulation sim(model, 0.001);
    const PoseError error = compare(sim, kdl_poses(kdl_tree(c.path), {}));
    EXPECT_LT(error.position_m, 1e-9) << error.worst;
    EXPECT_LT(error.rotation_rad, 1e-9) << error.worst;
    for (std::size_t j = 0; j < model.joints.size(); ++j)
      EXPECT_NEAR(sim.joint_position(j), 0.0, 1e-9) << model.joints[j].name;
  }
}

// Random targets within each joint's limits, commanded through the root body (as
// `afhub cmd` does), settled without gravity; then every link against KDL at the
// positions the simulation reports: the chain, not the controller, is checked.
TEST(Urdf, RandomCommandedConfigurationsMatchKdlWithin1e6) {
  std::mt19937 random(29);
  for (const Case& c : valid_cases()) {
    if (c.options.floating_base) continue;  // KDL reads floating and planar joints as fixed
    SCOPED_TRACE(c.path);
    Model model = load(c.path, c.options);
    // No gravity and no contacts (random configurations put links inside each
    // other): what remains is the chain's kinematics.
    override_gravity(model, {0, 0, 0});
    for (BodySpec& body : model.bodies) {
      body.collision_mesh.clear();
      body.collision_shapes.clear();
    }
    for (JointSpec& joint : model.joints) {
      joint.controller = {200.0, 0.0, 0.0};
      joint.controller_output = ControllerOutput::kVelocity;
      joint.max_motor_impulse = 10.0;
      joint.max_velocity.reset();  // settled within the trial's steps, at the UR5's pace not
    }
    Simulation sim(model, 0.001);
    const KDL::Tree tree = kdl_tree(c.path);
    std::size_t root = 0;
    for (std::size_t b = 0; b < model.bodies.size(); ++b)
      if (model.descendant_joints[b].size() > model.descendant_joints[root].size()) root = b;
    const std::vector<int>& below = model.descendant_joints[root];
    for (int trial = 0; trial < 20; ++trial) {
      BodyInput input;
      input.joint_count = static_cast<std::uint32_t>(below.size());
      for (std::size_t i = 0; i < below.size(); ++i) {
        const JointSpec& joint = model.joints[below[i]];
        input.joint_modes[i] = JointMode::kPosition;
        const double low = joint.limit_low.value_or(-3.0), high = joint.limit_high.value_or(3.0);
        input.joint_values[i] =
            has_joint_axis(joint.type) ? std::uniform_real_distribution(low, high)(random) : 0.0;
      }
      ASSERT_EQ(sim.input_problem(root, input), nullptr);
      sim.set_input(root, input);
      for (int step = 0; step < 3000; ++step) sim.step();
      std::map<std::string, double> q;
      for (std::size_t j = 0; j < model.joints.size(); ++j)
        q[model.joints[j].name] = sim.joint_position(j);
      const PoseError error = compare(sim, kdl_poses(tree, q));
      EXPECT_LT(error.position_m, 1e-6) << "trial " << trial << ": " << error.worst;
      EXPECT_LT(error.rotation_rad, 1e-6) << "trial " << trial << ": " << error.worst;
      ASSERT_TRUE(sim.all_finite());
    }
  }
}

// The real robots on the project's default gains: under gravity alone (the joints
// free: the arm swings down), then under position commands, nothing blows up, no
// joint comes apart at any step, none leaves its limits and nothing spins away. (The
// Allegro thumb came apart by 12.7 cm at step 15, its last joint at -5.7 rad against
// [-0.16, 1.72], when its second joint was given the damping of the whole thumb: the
// end of the run alone looked fine.)
TEST(Urdf, RealRobotsStayStableUnderGravityAndPositionCommands) {
  if (!fs::exists(kShared)) GTEST_SKIP() << kShared << " is absent";
  for (const std::string& urdf : {shared_urdf("ur_description/urdf/ur5_robot.urdf"),
                                  shared_urdf("allegro_hand_description/urdf/"
                                              "allegro_right_hand.urdf")}) {
    SCOPED_TRACE(urdf);
    const auto start = std::chrono::steady_clock::now();
    const Model model = load(urdf, {{kShared}, false});
    const auto loaded = std::chrono::steady_clock::now();
    Simulation sim(model, 0.001);  // reads the collision meshes
    const auto built = std::chrono::steady_clock::now();
    std::printf("urdf_test: %s loaded in %.1f ms, built with its meshes in %.1f ms more\n",
                fs::path(urdf).filename().c_str(),
                std::chrono::duration<double, std::milli>(loaded - start).count(),
                std::chrono::duration<double, std::milli>(built - loaded).count());
    std::vector<double> largest_gap(model.joints.size(), 0.0);
    auto run = [&](const char* phase) {
      SCOPED_TRACE(phase);
      for (int step = 0; step < 5000; ++step) {
        sim.step();
        for (std::size_t j = 0; j < model.joints.size(); ++j)
          largest_gap[j] = std::max(largest_gap[j], sim.joint_pivot_gap_m(j));
      }
      ASSERT_TRUE(sim.all_finite());
      EXPECT_EQ(sim.nan_recoveries().count, 0u);
      for (std::size_t j = 0; j < model.joints.size(); ++j) {
        const JointSpec& joint = model.joints[j];
        EXPECT_LT(largest_gap[j], 5e-3) << joint.name;
        EXPECT_LT(std::abs(sim.joint_velocity(j)), 20.0) << joint.name;
        if (joint.limit_low && joint.limit_high) {
          EXPECT_GT(sim.joint_position(j), *joint.limit_low - 0.05) << joint.name;
          EXPECT_LT(sim.joint_position(j), *joint.limit_high + 0.05) << joint.name;
        }
      }
    };
    run("gravity");
    std::size_t root = 0;
    for (std::size_t b = 0; b < model.bodies.size(); ++b)
      if (model.descendant_joints[b].size() > model.descendant_joints[root].size()) root = b;
    BodyInput input;
    input.joint_count = static_cast<std::uint32_t>(model.descendant_joints[root].size());
    for (std::size_t i = 0; i < input.joint_count; ++i) {
      input.joint_modes[i] = JointMode::kPosition;
      input.joint_values[i] = 0.3;
    }
    sim.set_input(root, input);
    run("position commands");
  }
}

// `afhub convert`'s ADF loads to the same bodies, joints and poses as the URDF.
TEST(Urdf, ConvertedAdfLoadsToTheSameRobotWithin1e9) {
  for (const Case& c : valid_cases()) {
    SCOPED_TRACE(c.path);
    const Model urdf = load(c.path, c.options);
    std::vector<std::string> lost;
    const fs::path adf = fs::temp_directory_path() / "afhub_urdf_test_converted.yaml";
    std::ofstream(adf) << adf_text(urdf, lost);
    const Model converted = load_adf_files({adf.string()});
    ASSERT_EQ(converted.bodies.size(), urdf.bodies.size());
    ASSERT_EQ(converted.joints.size(), urdf.joints.size());
    const Simulation a(urdf, 0.001), b(converted, 0.001);
    for (std::size_t i = 0; i < urdf.bodies.size(); ++i) {
      EXPECT_EQ(converted.bodies[i].channel, urdf.bodies[i].channel);
      EXPECT_EQ(converted.bodies[i].mass_kg, urdf.bodies[i].mass_kg);
      for (const auto parts : {&BodySpec::visual_mesh_parts, &BodySpec::collision_mesh_parts}) {
        const std::vector<PlacedMesh>&a_parts = urdf.bodies[i].*parts,
              &b_parts = converted.bodies[i].*parts;
        ASSERT_EQ(b_parts.size(), a_parts.size()) << urdf.bodies[i].name;
        for (std::size_t p = 0; p < a_parts.size(); ++p) {
          EXPECT_EQ(b_parts[p].path, a_parts[p].path);
          EXPECT_EQ(b_parts[p].offset.position_m.z, a_parts[p].offset.position_m.z);
          EXPECT_EQ(b_parts[p].offset.rpy_rad.z, a_parts[p].offset.rpy_rad.z);
          EXPECT_EQ(b_parts[p].scale.y, a_parts[p].scale.y);
        }
      }
      const Pose pa = a.body_pose(i), pb = b.body_pose(i);
      EXPECT_NEAR(pa.position_m.x, pb.position_m.x, 1e-9) << urdf.bodies[i].name;
      EXPECT_NEAR(pa.position_m.y, pb.position_m.y, 1e-9) << urdf.bodies[i].name;
      EXPECT_NEAR(pa.position_m.z, pb.position_m.z, 1e-9) << urdf.bodies[i].name;
      EXPECT_LT(angle_between(to_kdl(pa.orientation), to_kdl(pb.orientation)), 1e-9)
          << urdf.bodies[i].name;
    }
    for (std::size_t j = 0; j < urdf.joints.size(); ++j) {
      EXPECT_EQ(converted.joints[j].channel, urdf.joints[j].channel);
      EXPECT_EQ(converted.joints[j].type, urdf.joints[j].type);
      EXPECT_NEAR(b.joint_position(j), 0.0, 1e-9) << urdf.joints[j].name;
    }
    EXPECT_EQ(lost.size(), c.path.ends_with("gripper_mimic.urdf") ? 1u : 0u);
    fs::remove(adf);
  }
}

TEST(Urdf, ChannelsAreNamedFromRobotAndLinks) {
  const Model model = load(kModels + "/arm.urdf");
  ASSERT_EQ(model.bodies.size(), 6u);
  EXPECT_EQ(model.bodies[0].channel, "ambf/env/test_arm/base");
  EXPECT_EQ(model.bodies[5].channel, "ambf/env/test_arm/tool");
  EXPECT_EQ(model.joints[0].name, "yaw");
  EXPECT_EQ(model.descendant_joints[0].size(), 5u);
}

// A launch file listing a URDF arm beside an ADF gripper, with a world file and the
// arm placed by `at:`: one scene, as AMBF's launch files make with ADF files alone.
TEST(Urdf, ALaunchFileLoadsAUrdfBesideAdfAndAWorld) {
  const std::string examples = AFHUB_EXAMPLE_MODELS;
  const WrittenFile launch("launch.yaml",
                           "world config: " + examples + "/world.yaml\nmultibody configs:\n  - " +
                               kModels + "/arm.urdf\n  - " + examples + "/gripper.yaml\nat:\n  " +
                               kModels + "/arm.urdf: [1, 2, 0]\n");
  SceneRequest request;
  request.launch_file = launch.path;
  request.launch_indices = {0, 1};
  const Model model = load_scene(request);
  ASSERT_EQ(model.bodies.size(), 10u) << "the world's floor, 6 links, the gripper's 3 bodies";
  EXPECT_EQ(model.bodies[0].channel, "afhub/env/floor");
  EXPECT_EQ(model.bodies[1].channel, "ambf/env/test_arm/base");
  EXPECT_EQ(model.bodies[7].channel, "afhub/gripper/palm");
  EXPECT_EQ(model.world.lights.size(), 2u) << "the world file's";
  const Simulation sim(model, 0.001);
  EXPECT_NEAR(sim.body_pose(1).position_m.x, 1.0, 1e-12);
  EXPECT_NEAR(sim.body_pose(1).position_m.y, 2.0, 1e-12);
}

// As an ADF file loaded twice: the second copy's channels get an index, its joints too,
// and it simulates (its joints on its own bodies).
TEST(Urdf, TheSameUrdfTwiceLoadsAsACopy) {
  Model model;
  load_adf_files_into({kModels + "/arm.urdf", kModels + "/arm.urdf"}, model, {});
  ASSERT_EQ(model.bodies.size(), 12u);
  ASSERT_EQ(model.joints.size(), 10u);
  EXPECT_EQ(model.bodies[6].channel, "ambf/env/test_arm/base1");
  EXPECT_EQ(model.joints[5].channel, "ambf/env/test_arm/yaw1");
  EXPECT_EQ(model.joints[5].name, "yaw") << "a joint keeps its name";
  EXPECT_EQ(model.joints[5].parent, 6);
  EXPECT_EQ(model.joints[5].child, 7);
  Simulation sim(model, 0.001);
  sim.step();
  EXPECT_TRUE(std::isfinite(sim.joint_position(5)));
}

TEST(Urdf, LinksJointsAndRootMeanWhatUrdfSays) {
  const Model model = load(kModels + "/arm.urdf");
  const BodySpec& base = model.bodies[0];
  EXPECT_EQ(base.mass_kg, 0.0) << "the root is fixed by default";
  const BodySpec& upper = model.bodies[1];
  EXPECT_EQ(upper.mass_kg, 1.5);
  EXPECT_EQ(upper.visual_shapes.size(), 2u);
  EXPECT_EQ(upper.collision_shapes.size(), 2u);
  ASSERT_TRUE(upper.color_rgba);
  EXPECT_NEAR((*upper.color_rgba)[0], 0.8, 1e-6);  // urdfdom keeps floats
  // The principal moments of the off-diagonal tensor, which keep its trace.
  ASSERT_TRUE(upper.inertia_kgm2);
  EXPECT_NEAR(upper.inertia_kgm2->x + upper.inertia_kgm2->y + upper.inertia_kgm2->z, 0.065, 1e-12);
  const BodySpec& fore = model.bodies[2];
  EXPECT_EQ(fore.scale, 0.05);
  EXPECT_TRUE(fore.visual_mesh.ends_with("meshes/cube.obj"));
  ASSERT_EQ(fore.visual_mesh_parts.size(), 1u) << "its second <visual>, at its <origin>";
  EXPECT_TRUE(fore.visual_mesh_parts[0].path.ends_with("meshes/cube.obj"));
  EXPECT_EQ(fore.visual_mesh_parts[0].offset.position_m.z, 0.2);
  EXPECT_NEAR(fore.visual_mesh_parts[0].offset.rpy_rad.z, 0.5, 1e-12);
  EXPECT_EQ(fore.visual_mesh_parts[0].scale.z, 0.1) << "its own scale, taller";
  EXPECT_TRUE(fore.collision_mesh.ends_with("meshes/cube.obj"));
  EXPECT_EQ(model.bodies[5].mass_kg, 1e-3) << "a link without <inertial> is a frame";
  EXPECT_EQ(model.joints[0].type, JointType::kContinuous);
  EXPECT_EQ(model.joints[0].damping, 0.1);
  EXPECT_EQ(model.joints[1].type, JointType::kRevolute);
  EXPECT_EQ(*model.joints[1].limit_low, -2.0);
  EXPECT_EQ(model.joints[2].type, JointType::kPrismatic);
  EXPECT_EQ(model.joints[4].type, JointType::kFixed);
  for (const JointSpec& joint : model.joints) EXPECT_TRUE(joint.ignore_inter_collision);
  // Each ignored element once, located.
  std::string warnings;
  for (const auto& warning : model.warnings) warnings += warning + "\n";
  for (const char* what :
       {"<transmission>", "<gazebo>", "<safety_controller>", "<calibration>", "friction"})
    EXPECT_NE(warnings.find(what), std::string::npos) << what << " in\n" << warnings;
  EXPECT_NE(warnings.find("arm.urdf:"), std::string::npos);
  std::string notes;
  for (const auto& note : model.notes) notes += note + "\n";
  EXPECT_NE(notes.find("root link 'base' is fixed to the world"), std::string::npos) << notes;
  EXPECT_NE(notes.find("do not collide"), std::string::npos) << notes;
}

TEST(Urdf, FloatingBaseFreesTheRootAndAWorldRootStaysFixed) {
  const Model fixed = load(kModels + "/floating_planar.urdf");
  EXPECT_EQ(fixed.bodies[0].mass_kg, 0.0);
  Model free = load(kModels + "/floating_planar.urdf", {{}, true});
  EXPECT_EQ(free.bodies[0].mass_kg, 3.0);
  EXPECT_EQ(free.joints[0].type, JointType::kSixDof);  // planar
  ASSERT_TRUE(free.joints[0].multi_limits);
  EXPECT_FALSE(free.joints[1].multi_limits);  // floating: every direction free
  {  // At load, each link where its joint's origin puts it.
    const Simulation at_load(free, 0.001);
    const Pose drone = at_load.body_pose(2), puck = at_load.body_pose(1);
    EXPECT_NEAR(drone.position_m.x, 0.5, 1e-12);
    EXPECT_NEAR(drone.orientation.z, std::sin(0.35), 1e-12);
    EXPECT_NEAR(puck.position_m.z, 0.2, 1e-12);
    EXPECT_NEAR(puck.orientation.y, std::sin(0.15), 1e-12);
  }
  // The free robot falls under gravity; the planar puck keeps its plane's height
  // above the body.
  Simulation sim(free, 0.001);
  for (int step = 0; step < 200; ++step) sim.step();
  EXPECT_LT(sim.body_pose(0).position_m.z, -0.1);
  if (fs::exists(kShared)) {
    const Model ur5 = load(shared_urdf("ur_description/urdf/ur5_robot.urdf"), {{kShared}, true});
    std::string notes;
    for (const auto& note : ur5.notes) notes += note;
    EXPECT_NE(notes.find("root link 'world' is fixed"), std::string::npos) << notes;
  }
}

TEST(Urdf, AMimicJointFollowsItsLeader) {
  Model model = load(kModels + "/gripper_mimic.urdf");
  override_gravity(model, {0, 0, 0});
  ASSERT_TRUE(model.joints[1].mimic);
  EXPECT_EQ(model.joints[1].mimic->joint, 0);
  for (JointSpec& joint : model.joints) {
    joint.controller = {200.0, 0.0, 0.0};
    joint.controller_output = ControllerOutput::kVelocity;
  }
  Simulation sim(model, 0.001);
  BodyInput input;
  input.joint_count = 1;
  input.joint_modes[0] = JointMode::kPosition;
  input.joint_values[0] = 0.03;
  sim.set_input(0, input);
  for (int step = 0; step < 2000; ++step) sim.step();
  EXPECT_NEAR(sim.joint_position(0), 0.03, 1e-4);
  EXPECT_NEAR(sim.joint_position(1), 0.5 * sim.joint_position(0) + 0.01, 1e-4);
}

// <limit velocity> caps the joint's speed (it was read and dropped: a joint limited to
// 0.5 rad/s turned at 32.8 rad/s under a position command, in an exploratory run). A
// velocity of 0, which many files give for none, caps nothing; convert keeps the cap.
std::string spinner_urdf(double velocity) {
  return "<robot name=\"spinner\"><link name=\"base\"><inertial><mass value=\"1\"/><inertia "
         "ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>"
         "<link name=\"arm\"><inertial><mass value=\"1\"/><inertia ixx=\"0.01\" iyy=\"0.01\" "
         "izz=\"0.01\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>"
         "<joint name=\"spin\" type=\"revolute\"><parent link=\"base\"/><child link=\"arm\"/>"
         "<axis xyz=\"0 0 1\"/><limit lower=\"-3\" upper=\"3\" effort=\"50\" velocity=\"" +
         std::to_string(velocity) + "\"/></joint></robot>";
}

// The fastest the joint turns in `steps` under a command of `mode` to `value`, and where
// it ends.
std::pair<double, double> fastest_and_last(Model model, JointMode mode, double value, int steps) {
  model.joints[0].controller = {200.0, 0.0, 5.0};
  Simulation sim(model, 0.001);
  BodyInput input;
  input.joint_count = 1;
  input.joint_modes[0] = mode;
  input.joint_values[0] = value;
  sim.set_input(static_cast<std::size_t>(model.joints[0].parent), input);  // the joint's body
  double fastest = 0.0;
  for (int step = 0; step < steps; ++step) {
    sim.step();
    fastest = std::max(fastest, std::abs(sim.joint_velocity(0)));
  }
  return {fastest, sim.joint_position(0)};
}

TEST(Urdf, AVelocityLimitCapsTheJointsSpeed) {
  const WrittenFile capped("spinner.urdf", spinner_urdf(0.5));
  const Model model = load(capped.path);
  ASSERT_TRUE(model.joints[0].max_velocity);
  EXPECT_EQ(*model.joints[0].max_velocity, 0.5);
  const auto [position_fastest, position_last] =
      fastest_and_last(model, JointMode::kPosition, 2.0, 2000);
  EXPECT_LE(position_fastest, 0.55);
  EXPECT_GT(position_last, 0.8) << "it moved at about its cap";
  const auto [velocity_fastest, velocity_last] =
      fastest_and_last(model, JointMode::kVelocity, 2.0, 500);
  EXPECT_LE(velocity_fastest, 0.5 + 1e-6);
  EXPECT_NEAR(velocity_last, 0.25, 0.02) << "0.5 s at 0.5 rad/s";

  const WrittenFile uncapped("spinner0.urdf", spinner_urdf(0.0));
  const Model free_model = load(uncapped.path);
  EXPECT_FALSE(free_model.joints[0].max_velocity);
  EXPECT_GT(fastest_and_last(free_model, JointMode::kPosition, 2.0, 2000).first, 2.0);

  std::vector<std::string> lost;
  const WrittenFile adf("spinner.yaml", adf_text(model, lost));
  const Model converted = load(adf.path);
  ASSERT_TRUE(converted.joints[0].max_velocity);
  EXPECT_EQ(*converted.joints[0].max_velocity, 0.5);
}

// The cap takes nothing from holding: a lift capped at 5 mm/s holds its 1 kg platform
// against gravity as an uncapped one does (a cap reckoned from the speed one step could
// reach sagged a UR5's shoulder by 0.4 rad, and let a loaded lift fall at 3x its cap),
// then rises at the cap.
TEST(Urdf, AVelocityLimitTakesNothingFromHoldingAgainstGravity) {
  const auto lift = [](double velocity) {
    return "<robot name=\"lift\"><link name=\"base\"><inertial><mass value=\"1\"/><inertia "
           "ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>"
           "</link><link name=\"platform\"><inertial><mass value=\"1\"/><inertia ixx=\"0.01\" "
           "iyy=\"0.01\" izz=\"0.01\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>"
           "<joint name=\"lift\" type=\"prismatic\"><parent link=\"base\"/><child "
           "link=\"platform\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" "
           "effort=\"100\" velocity=\"" +
           std::to_string(velocity) + "\"/></joint></robot>";
  };
  // Held at 0 for a second, then sent to 0.3 m for two: the sag, the fastest rise, the end.
  const auto run = [](const std::string& path) {
    Model model = load(path);
    model.joints[0].controller = {2000.0, 0.0, 50.0};
    Simulation sim(model, 0.001);
    BodyInput input;
    input.joint_count = 1;
    input.joint_modes[0] = JointMode::kPosition;
    input.joint_values[0] = 0.0;
    const auto body = static_cast<std::size_t>(model.joints[0].parent);
    sim.set_input(body, input);
    for (int step = 0; step < 1000; ++step) sim.step();
    const double sag = sim.joint_position(0);
    input.joint_values[0] = 0.3;
    sim.set_input(body, input);
    double fastest = 0.0;
    for (int step = 0; step < 2000; ++step) {
      sim.step();
      fastest = std::max(fastest, std::abs(sim.joint_velocity(0)));
    }
    return std::array{sag, fastest, sim.joint_position(0)};
  };
  constexpr double kCap = 0.005;  // m/s: at most 5 N at rest, reckoned from one step's reach
  const WrittenFile capped("lift.urdf", lift(kCap)), free("lift0.urdf", lift(0.0));
  const auto [capped_sag, capped_fastest, capped_end] = run(capped.path);
  const auto [free_sag, free_fastest, free_end] = run(free.path);
  std::printf(
      "lift held at 0: sag %.4f m capped, %.4f m uncapped; fastest %.3f / %.3f m/s; "
      "after 2 s at %.3f / %.3f m\n",
      capped_sag, free_sag, capped_fastest, free_fastest, capped_end, free_end);
  EXPECT_LT(std::abs(free_sag), 0.01);
  EXPECT_NEAR(capped_sag, free_sag, 1e-3) << "the cap took from the hold";
  EXPECT_LE(capped_fastest, kCap * 1.01);
  EXPECT_GT(free_fastest, 0.5);
  EXPECT_NEAR(capped_end - capped_sag, 2 * kCap, 0.2 * kCap) << "two seconds at the cap";
}

TEST(Urdf, BadFilesGetALocatedErrorNamingTheProblem) {
  const std::string missing = load_error(kModels + "/missing_mesh.urdf");
  EXPECT_NE(missing.find("missing_mesh.urdf:4:3: error: link 'base'"), std::string::npos)
      << missing;
  EXPECT_NE(missing.find("package://no_such_package/meshes/base.stl"), std::string::npos)
      << missing;
  EXPECT_NE(missing.find("ROS_PACKAGE_PATH"), std::string::npos) << missing;
  const std::string cycle = load_error(kModels + "/cycle.urdf");
  EXPECT_NE(cycle.find("cycle.urdf:3:1: error: not a valid URDF"), std::string::npos) << cycle;
  const std::string malformed = load_error(kModels + "/malformed.urdf");
  EXPECT_NE(malformed.find("malformed.urdf:6:3: error: not well-formed XML"), std::string::npos)
      << malformed;
  const std::string xacro = load_error(kModels + "/robot.urdf.xacro");
  EXPECT_NE(xacro.find("expand it to a URDF first"), std::string::npos) << xacro;
  const std::string absent = load_error(kModels + "/absent.urdf");
  EXPECT_NE(absent.find("does not exist"), std::string::npos) << absent;
  // With the package given, the same mesh name is looked for there.
  const std::string given = load_error(kModels + "/missing_mesh.urdf", {{"/nonexistent"}, false});
  EXPECT_NE(given.find("no package 'no_such_package'"), std::string::npos) << given;
}

// Each mistake at its own line and column, with what is wrong: XML that is not
// well-formed (TinyXML's place) and what urdfdom refuses (at the link or joint it
// names, down to the element holding the value it quotes).
TEST(Urdf, MalformedAndInvalidFilesAreErrorsAtTheirLine) {
  const std::string head = "<?xml version=\"1.0\"?>\n<robot name=\"bad\">\n  <link name=\"a\"/>\n";
  struct Bad {
    std::string name, body, where, what;
  };
  const std::vector<Bad> cases = {
      {"unclosed.urdf", "  <link name=\"b\">\n    <inertial><mass value=\"1\"/>\n  </link>\n",
       ":6:3: error: not well-formed XML (error reading end tag)", "a tag left open"},
      {"quote.urdf", "  <link name=\"b/>\n",
       ":4:9: error: not well-formed XML (error parsing element)", "a missing quote"},
      {"no_parent.urdf",
       "  <link name=\"b\"/>\n  <joint name=\"j\" type=\"fixed\">\n    <child link=\"b\"/>\n"
       "  </joint>\n",
       ":5:3: error: not a valid URDF", "Joint [j] is missing a parent"},
      {"unknown_link.urdf",
       "  <joint name=\"j\" type=\"fixed\">\n    <parent link=\"a\"/>\n    <child "
       "link=\"nowhere\"/>\n  </joint>\n",
       ":6:5: error: not a valid URDF", "child link [nowhere] of joint [j] not found"},
      {"bad_mass.urdf",
       "  <link name=\"b\">\n    <inertial>\n      <mass value=\"1.x\"/>\n    </inertial>\n  "
       "</link>\n",
       ":6:7: error: not a valid URDF", "mass [1.x] is not a float"},
      {"bad_origin.urdf",
       "  <link name=\"b\"/>\n  <joint name=\"j\" type=\"fixed\">\n    <parent link=\"a\"/>\n"
       "    <child link=\"b\"/>\n    <origin xyz=\"0 0 abc\"/>\n  </joint>\n",
       ":8:5: error: not a valid URDF", "[abc]"},
      {"bad_limit.urdf",
       "  <link name=\"b\"/>\n  <joint name=\"j\" type=\"revolute\">\n    <parent "
       "link=\"a\"/>\n    <child link=\"b\"/>\n    <limit lower=\"-1\" upper=\"one\" "
       "effort=\"1\" velocity=\"1\"/>\n  </joint>\n",
       ":8:5: error: not a valid URDF", "upper value (one) is not a valid float"},
      // urdfdom drops an element it cannot read, says so and returns the robot.
      {"tiny_mass.urdf",
       "  <link name=\"b\">\n    <inertial>\n      <mass value=\"1e-300\"/>\n      <inertia "
       "ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/>\n    </inertial>\n  "
       "</link>\n  <joint name=\"j\" type=\"fixed\">\n    <parent link=\"a\"/>\n    <child "
       "link=\"b\"/>\n  </joint>\n",
       ":4:3: error: link 'b': <mass> is 1e-300 kg, below the 1e-09 kg a moving link needs",
       "Bullet divides by it"},
      {"nan_mass.urdf",
       "  <link name=\"b\">\n    <inertial>\n      <mass value=\"nan\"/>\n    </inertial>\n  "
       "</link>\n",
       ":6:7: error: not a valid URDF", "mass [nan] is not a float"},
      // Values Bullet's arithmetic cannot take, within an ADF file's bounds.
      {"zero_box.urdf",
       "  <link name=\"b\">\n    <collision><geometry><box size=\"0 1 1\"/></geometry>"
       "</collision>\n  </link>\n  <joint name=\"j\" type=\"fixed\">\n    <parent link=\"a\"/>\n"
       "    <child link=\"b\"/>\n  </joint>\n",
       ":4:3: error: link 'b': <box size> side is 0", "give a size above 0"},
      {"zero_axis.urdf",
       "  <link name=\"b\"/>\n  <joint name=\"j\" type=\"revolute\">\n    <parent link=\"a\"/>\n"
       "    <child link=\"b\"/>\n    <axis xyz=\"0 0 0\"/>\n    <limit lower=\"-1\" upper=\"1\" "
       "effort=\"1\" velocity=\"1\"/>\n  </joint>\n",
       ":5:3: error: joint 'j': its <axis> is zero", "<axis xyz=\"0 0 1\"/>"},
      // urdfdom turned it into some rotation.
      {"huge_rpy.urdf",
       "  <link name=\"b\"/>\n  <joint name=\"j\" type=\"fixed\">\n    <parent link=\"a\"/>\n"
       "    <child link=\"b\"/>\n    <origin rpy=\"1e300 0 0\"/>\n  </joint>\n",
       ":8:5: error: <origin rpy=\"1e300 0 0\"> holds 1e+300", "give radians within 1e+06"},
      {"huge_effort.urdf",
       "  <link name=\"b\"/>\n  <joint name=\"j\" type=\"revolute\">\n    <parent link=\"a\"/>\n"
       "    <child link=\"b\"/>\n    <axis xyz=\"0 0 1\"/>\n    <limit lower=\"-1\" upper=\"1\" "
       "effort=\"1e300\" velocity=\"1\"/>\n  </joint>\n",
       ":5:3: error: joint 'j': <limit effort> is 1e+300", "give a number from 0 to 1e+09"},
      // urdfdom takes these two (one root is left); the walk from the root refuses them.
      {"own_child.urdf",
       "  <link name=\"b\"/>\n  <joint name=\"ab\" type=\"fixed\">\n    <parent "
       "link=\"a\"/>\n    <child link=\"b\"/>\n  </joint>\n  <joint name=\"bb\" "
       "type=\"fixed\">\n    <parent link=\"b\"/>\n    <child link=\"b\"/>\n  </joint>\n",
       ":9:3: error: joint 'bb' has link 'b' as both its parent and its child",
       "a joint joins two different links"},
      // urdfdom takes the other link for the root: 'map::at' was all that was said.
      {"own_child_alone.urdf",
       "  <link name=\"b\"/>\n  <joint name=\"bb\" type=\"fixed\">\n    <parent "
       "link=\"b\"/>\n    <child link=\"b\"/>\n  </joint>\n",
       ":5:3: error: joint 'bb' has link 'b' as both its parent and its child",
       "a joint joins two different links"},
      {"cycle.urdf",
       "  <link name=\"b\"/>\n  <link name=\"c\"/>\n  <joint name=\"bc\" type=\"fixed\">\n"
       "    <parent link=\"b\"/>\n    <child link=\"c\"/>\n  </joint>\n  <joint name=\"cb\" "
       "type=\"fixed\">\n    <parent link=\"c\"/>\n    <child link=\"b\"/>\n  </joint>\n",
       ":4:3: error: link 'b' is not below the root link 'a': its joints close a cycle",
       "each the child of one joint"},
      {"two_parents.urdf",
       "  <link name=\"b\"/>\n  <link name=\"c\"/>\n  <joint name=\"ab\" type=\"fixed\">\n"
       "    <parent link=\"a\"/>\n    <child link=\"b\"/>\n  </joint>\n  <joint name=\"ac\" "
       "type=\"fixed\">\n    <parent link=\"a\"/>\n    <child link=\"c\"/>\n  </joint>\n"
       "  <joint name=\"cb\" type=\"fixed\">\n    <parent link=\"c\"/>\n    <child "
       "link=\"b\"/>\n  </joint>\n",
       ":14:3: error: joint 'cb' makes link 'b' a child a second time: it is the child of "
       "joint 'ab'",
       "remove one of the two"},
  };
  for (const Bad& bad : cases) {
    SCOPED_TRACE(bad.name);
    const WrittenFile file(bad.name, head + bad.body + "</robot>\n");
    const std::string error = load_error(file.path);
    EXPECT_TRUE(error.starts_with(file.path + bad.where)) << error;
    EXPECT_NE(error.find(bad.what), std::string::npos) << error;
  }
  // Moments no rigid body has load, with a warning, as in an ADF file.
  const WrittenFile flat(
      "flat.urdf",
      head +
          "  <link name=\"b\">\n    <inertial>\n      <mass value=\"1\"/>\n      <inertia "
          "ixx=\"1\" iyy=\"1\" izz=\"5\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/>\n    </inertial>\n"
          "  </link>\n  <joint name=\"j\" type=\"fixed\">\n    <parent link=\"a\"/>\n    "
          "<child link=\"b\"/>\n  </joint>\n</robot>\n");
  const Model flat_model = load(flat.path);
  ASSERT_EQ(flat_model.warnings.size(), 1u);
  EXPECT_TRUE(flat_model.warnings[0].starts_with(
      flat.path + ":4:1: warning: link 'b': its <inertia> has principal moments (1, 1, 5)"))
      << flat_model.warnings[0];
  // Degrees where URDF takes radians load, with a warning each.
  const WrittenFile degrees(
      "degrees.urdf",
      head +
          "  <link name=\"b\"/>\n  <joint name=\"j\" type=\"revolute\">\n    <parent "
          "link=\"a\"/>\n    <child link=\"b\"/>\n    <origin rpy=\"90 0 0\"/>\n    <limit "
          "lower=\"-90\" upper=\"90\" effort=\"1\" velocity=\"1\"/>\n  </joint>\n</robot>\n");
  const Model degrees_model = load(degrees.path);
  ASSERT_EQ(degrees_model.warnings.size(), 2u);
  EXPECT_NE(degrees_model.warnings[0].find(":8:1: warning: <origin rpy=\"90 0 0\"> turns more "
                                           "than a full turn"),
            std::string::npos)
      << degrees_model.warnings[0];
  EXPECT_NE(degrees_model.warnings[1].find("reaches past a full turn"), std::string::npos)
      << degrees_model.warnings[1];
  const WrittenFile not_robot("not_robot.urdf", "<?xml version=\"1.0\"?>\n<model name=\"m\"/>\n");
  EXPECT_EQ(load_error(not_robot.path),
            not_robot.path +
                ":2:1: error: the top element is not <robot name=\"...\">; is this "
                "a URDF file?");
  // Declarations in a DOCTYPE are said as such (they were "not <robot>" at 1:1); a
  // DOCTYPE without them loads.
  const std::string robot = "<robot name=\"r\">\n  <link name=\"a\"/>\n</robot>\n";
  const WrittenFile entities("entities.urdf",
                             "<?xml version=\"1.0\"?>\n<!DOCTYPE robot [\n  <!ENTITY len "
                             "\"0.5\">\n]>\n" +
                                 robot);
  const std::string declared = load_error(entities.path);
  EXPECT_TRUE(declared.starts_with(entities.path + ":2:1: error: this DOCTYPE declares entities"))
      << declared;
  const WrittenFile plain("doctype.urdf", "<?xml version=\"1.0\"?>\n<!DOCTYPE robot>\n" + robot);
  EXPECT_EQ(load(plain.path).bodies.size(), 1u);
  // A package:// path that climbs out of its package is refused, not followed.
  for (const std::string uri :
       {"package://bad/../../../etc/passwd", "package://bad//etc/passwd", "package://../x.stl"}) {
    const WrittenFile climbing(
        "climbing.urdf", head + "  <link name=\"b\">\n    <visual><geometry><mesh filename=\"" +
                             uri +
                             "\"/></geometry></visual>\n  </link>\n  <joint name=\"j\" "
                             "type=\"fixed\">\n    <parent link=\"a\"/>\n    <child "
                             "link=\"b\"/>\n  </joint>\n</robot>\n");
    const std::string climbed = load_error(climbing.path);
    EXPECT_TRUE(climbed.starts_with(climbing.path + ":4:3: error: link 'b': visual mesh '" + uri +
                                    "' leads out of its package"))
        << climbed;
  }
}

// A mesh named relative to the URDF, the URDF named relative to the working folder (as
// `afhub convert arm.urdf -o elsewhere/arm.yaml` from its folder): the mesh's path is
// absolute, so that the ADF written elsewhere finds it (it said "meshes/cube.obj").
TEST(Urdf, MeshPathsAreAbsoluteWhereverTheFileIsNamedFrom) {
  const fs::path before = fs::current_path();
  fs::current_path(kModels);
  std::string mesh;
  try {
    mesh = load("arm.urdf").bodies[2].collision_mesh;
  } catch (...) {
    fs::current_path(before);
    throw;
  }
  fs::current_path(before);
  EXPECT_EQ(mesh, (fs::absolute(kModels) / "meshes/cube.obj").lexically_normal().string());
}

// TinyXML reads nested elements by recursion: 50 000 levels crashed the loader (stack
// overflow). Refused before it parses, at the element past the limit; comments and
// quoted values holding '>' are not counted.
TEST(Urdf, ElementsNestedPastTheLimitAreAnErrorNotACrash) {
  const std::string before = "<!-- <x> <x> --><y a=\"x>\" b='/>'/>";
  std::string deep = before;
  for (int i = 0; i < 50'000; ++i) deep += "<x>";
  for (int i = 0; i < 50'000; ++i) deep += "</x>";
  const WrittenFile file("deep.urdf",
                         "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n  <link "
                         "name=\"a\"/>\n" +
                             deep + "\n</robot>\n");
  // <robot> is the first level: the 1000th <x> the 1001st, after the comment and <y/>.
  const std::size_t column = before.size() + 999 * 3 + 1;
  const std::string error = load_error(file.path);
  EXPECT_TRUE(error.starts_with(file.path + ":4:" + std::to_string(column) +
                                ": error: XML elements nested deeper than 1000 levels"))
      << error;
}

// Several collision meshes on one link, each at its <origin>, beside a sphere: one
// compound. Two cubes 0.6 m apart, 0.5 m below the link frame, land the block level
// on a floor 1 m below it (a single cube under the centre of mass, or the meshes at
// the link frame, would land it elsewhere or tipped).
// Two cubes 0.3 m tall (each scaled per axis, differently in x, one mirrored in y: a
// negative scale, as RViz and Gazebo take it, was refused) under a block, and a small
// sphere: the block rests on the cubes.
TEST(Urdf, SeveralPlacedCollisionMeshesCollideAsOneCompound) {
  const std::string cube = kModels + "/meshes/cube.obj";
  auto mesh = [&](const std::string& xyz, const std::string& scale) {
    return "<collision><origin xyz=\"" + xyz + "\"/><geometry><mesh filename=\"" + cube +
           "\" scale=\"" + scale + "\"/></geometry></collision>";
  };
  const WrittenFile floor("floor.urdf",
                          "<robot name=\"ground\"><link name=\"world\"><collision><origin "
                          "xyz=\"0 0 -1.1\"/><geometry><box size=\"3 3 0.2\"/></geometry>"
                          "</collision></link></robot>\n");
  const WrittenFile block(
      "block.urdf",
      "<robot name=\"block\"><link name=\"block\"><inertial><mass value=\"1\"/>"
      "<inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" "
      "izz=\"0.01\"/></inertial>" +
          mesh("0.3 0 -0.5", "0.2 -0.1 0.3") + mesh("-0.3 0 -0.5", "0.1 0.1 0.3") +
          "<collision><geometry><sphere radius=\"0.05\"/></geometry></collision>"
          "</link></robot>\n");
  Model model;
  load_adf_files_into({floor.path, block.path}, model, {{}, true});
  ASSERT_EQ(model.bodies.size(), 2u);
  const BodySpec& spec = model.bodies[1];
  EXPECT_TRUE(spec.collision_mesh.empty());
  ASSERT_EQ(spec.collision_mesh_parts.size(), 2u);
  EXPECT_EQ(spec.collision_mesh_parts[0].offset.position_m.x, 0.3);
  EXPECT_EQ(spec.collision_mesh_parts[0].scale.x, 0.2);
  EXPECT_EQ(spec.collision_mesh_parts[1].scale.x, 0.1);
  EXPECT_EQ(spec.collision_shapes.size(), 1u);
  Simulation sim(model, 0.001);
  for (int step = 0; step < 3000; ++step) sim.step();
  const Pose pose = sim.body_pose(1);
  EXPECT_NEAR(pose.position_m.z, -0.35, 5e-3);  // the cubes' bottoms on the floor
  EXPECT_NEAR(pose.position_m.x, 0.0, 5e-3);
  EXPECT_LT(angle_between(to_kdl(pose.orientation), KDL::Rotation::Identity()), 1e-2);
  // Converted (the floor and the block in one file), the block keeps its placed meshes
  // (afhub's `collision meshes` key) and lands the same way.
  std::vector<std::string> lost;
  const WrittenFile adf("block.yaml", adf_text(model, lost));
  EXPECT_TRUE(lost.empty());
  const Model converted = load_adf_files({adf.path});
  ASSERT_EQ(converted.bodies.size(), 2u);
  const BodySpec& read_back = converted.bodies[1];
  ASSERT_EQ(read_back.collision_mesh_parts.size(), 2u);
  EXPECT_EQ(read_back.collision_mesh_parts[1].path, spec.collision_mesh_parts[1].path);
  EXPECT_EQ(read_back.collision_mesh_parts[1].offset.position_m.x, -0.3);
  EXPECT_EQ(read_back.collision_mesh_parts[0].scale.x, 0.2);
  EXPECT_EQ(read_back.collision_mesh_parts[0].scale.z, 0.3);
  EXPECT_EQ(read_back.collision_mesh_parts[0].scale.y, -0.1);
  Simulation again(converted, 0.001);
  for (int step = 0; step < 3000; ++step) again.step();
  EXPECT_NEAR(again.body_pose(1).position_m.z, pose.position_m.z, 1e-6);
}

// Elements afhub does not read are said, once per kind, at their line: a <sensor>, a
// misspelt <colision> (its link then collided as nothing), anything unknown (they went
// by without a word; <transmission> and <gazebo> were said).
TEST(Urdf, ElementsItDoesNotReadAreSaidAtTheirLine) {
  const WrittenFile file(
      "unread.urdf",
      "<robot name=\"u\">\n"
      "  <link name=\"base\"><inertial><mass value=\"1\"/><inertia ixx=\"0.01\" iyy=\"0.01\" "
      "izz=\"0.01\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>\n"
      "    <colision><geometry><box size=\"1 1 1\"/></geometry></colision></link>\n"
      "  <sensor name=\"s\"/>\n  <sensor name=\"t\"/>\n  <transmission name=\"x\"/>\n"
      "  <joint name=\"j\" type=\"fixed\"><parent link=\"base\"/><child link=\"a\"/><bar/>"
      "</joint>\n  <link name=\"a\"/>\n</robot>\n");
  const Model model = load(file.path);
  std::string warnings;
  for (const std::string& warning : model.warnings) warnings += warning + "\n";
  for (const char* said :
       {":3:1: warning: <colision> elements in a link are not read",
        ":4:1: warning: <sensor> elements are not read (afhub reads <link>, <joint> and",
        ":6:1: warning: <transmission> elements are ignored",
        ":7:1: warning: <bar> elements in a joint are not read"})
    EXPECT_NE(warnings.find(said), std::string::npos) << said << "\n" << warnings;
  EXPECT_EQ(std::count(warnings.begin(), warnings.end(), '\n'), 4) << "once per kind:\n"
                                                                   << warnings;
}

// A mirrored mesh keeps its triangles facing out: the cube's volume, summed from its
// triangles' windings, is the same mirrored (it came out negative, inside out).
TEST(Urdf, AMirroredMeshIsWoundOutward) {
  const std::string cube = kModels + "/meshes/cube.obj";
  const auto volume = [&](const Vec3& scale) {
    const TriangleMesh mesh = load_body_meshes({{cube, scale, {}, "test"}}).at(0);
    double sum = 0.0;
    for (const auto& [a, b, c] : mesh.triangles) {
      const auto& p = mesh.vertices[a];
      const auto& q = mesh.vertices[b];
      const auto& r = mesh.vertices[c];
      sum += p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) +
             p[2] * (q[0] * r[1] - q[1] * r[0]);
    }
    return sum / 6.0;
  };
  const double plain = volume({0.2, 0.1, 0.3});
  EXPECT_GT(plain, 0.0);
  EXPECT_NEAR(volume({0.2, -0.1, 0.3}), plain, 1e-12);
  EXPECT_NEAR(volume({-0.2, -0.1, -0.3}), plain, 1e-12);
  EXPECT_NEAR(volume({-0.2, -0.1, 0.3}), plain, 1e-12) << "two axes: a turn, not a mirror";
}

// --mesh-fallback box: a link with a collision mesh that cannot be used (no
// triangles) collides as one box instead of its meshes, beside its primitive shapes.
TEST(Urdf, ALinkWithAnUnusableCollisionMeshFallsBackToABox) {
  const WrittenFile empty("empty.stl", "solid empty\nendsolid empty\n");
  const std::string cube = kModels + "/meshes/cube.obj";
  const WrittenFile link(
      "broken.urdf",
      "<robot name=\"broken\"><link name=\"block\"><inertial><mass value=\"1\"/>"
      "<inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/>"
      "</inertial><collision><origin xyz=\"0.3 0 0\"/><geometry><mesh filename=\"" +
          cube +
          "\" scale=\"0.1 0.1 0.1\"/></geometry></collision><collision><geometry><mesh "
          "filename=\"" +
          empty.path +
          "\"/></geometry></collision><collision><geometry><sphere "
          "radius=\"0.05\"/></geometry></collision></link></robot>\n");
  Model model = load(link.path);
  ASSERT_EQ(model.bodies.at(0).collision_mesh_parts.size(), 2u);
  const std::vector<std::string> warnings = fall_back_to_boxes(model);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("it collides as a box"), std::string::npos) << warnings[0];
  const BodySpec& body = model.bodies[0];
  EXPECT_TRUE(body.collision_mesh_parts.empty());
  ASSERT_EQ(body.collision_shapes.size(), 2u) << "the sphere, then the box";
  EXPECT_EQ(body.collision_shapes[1].kind, ShapeKind::kBox);
  Simulation sim(model, 0.001);
  sim.step();
}

TEST(Urdf, PackagesResolveThroughPackagePathAndRosPackagePath) {
  if (!fs::exists(kShared)) GTEST_SKIP() << kShared << " is absent";
  const std::string ur5 = shared_urdf("ur_description/urdf/ur5_robot.urdf");
  EXPECT_EQ(load(ur5).bodies.size(), 11u) << "found walking up from the URDF's folder";
  // A copy elsewhere finds its package only through a search path.
  const fs::path copy = fs::temp_directory_path() / "afhub_urdf_test_ur5.urdf";
  fs::copy_file(ur5, copy, fs::copy_options::overwrite_existing);
  EXPECT_NE(load_error(copy.string()).find("was not found"), std::string::npos);
  EXPECT_EQ(load(copy.string(), {{kShared}, false}).bodies.size(), 11u);
  setenv("ROS_PACKAGE_PATH", ("/nonexistent:" + kShared).c_str(), 1);
  EXPECT_EQ(load(copy.string()).bodies.size(), 11u);
  unsetenv("ROS_PACKAGE_PATH");
  fs::remove(copy);
}

// The hub publishes 450 bodies at most, but a model of 1000 links loads (and so
// `afhub check` reads it) with no quadratic step.
TEST(Urdf, AThousandLinkChainLoads) {
  const fs::path path = fs::temp_directory_path() / "afhub_urdf_test_chain.urdf";
  {
    std::ofstream out(path);
    out << "<robot name=\"chain\">\n";
    for (int i = 0; i < 1000; ++i) {
      out << "<link name=\"l" << i << "\"><inertial><mass value=\"0.1\"/><inertia ixx=\"1e-4\" "
          << "ixy=\"0\" ixz=\"0\" iyy=\"1e-4\" iyz=\"0\" izz=\"1e-4\"/></inertial></link>\n";
      if (i > 0)
        out << "<joint name=\"j" << i << "\" type=\"revolute\"><parent link=\"l" << i - 1
            << "\"/><child link=\"l" << i << "\"/><origin xyz=\"0 0 0.01\" rpy=\"0 0 0.1\"/>"
            << "<axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" "
            << "velocity=\"1\"/></joint>\n";
    }
    out << "</robot>\n";
  }
  const auto start = std::chrono::steady_clock::now();
  const Model model = load(path.string());
  // A figure for docs/urdf.md, not a check: this machine's load varies.
  std::printf(
      "urdf_test: the 1000-link chain loaded in %.1f ms\n",
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  EXPECT_EQ(model.bodies.size(), 1000u);
  EXPECT_EQ(model.joints.size(), 999u);
  EXPECT_EQ(model.bodies[999].channel, "ambf/env/chain/l999");
  const Simulation sim(model, 0.001);
  const PoseError error = compare(sim, kdl_poses(kdl_tree(path.string()), {}));
  EXPECT_LT(error.position_m, 1e-9);
  fs::remove(path);
}

}  // namespace
}  // namespace afhub::physics
