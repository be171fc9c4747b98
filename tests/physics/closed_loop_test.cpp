// Joints that hold together, and NaNs that do not end the world: an open chain of
// light and heavy links swinging free, solved directly and iterated; the da Vinci
// ECM of the seed paper (three loops, a prismatic insertion, a p2p joint) at rest
// and under 1 kHz sinusoid position commands, and stress models of our own. The
// stress models are slider-cranks (a loop with a prismatic joint) whose bodies sit
// at arbitrary orientations, so each joint's axis differs between the parent, the
// child and Bullet's constraint axis, as in models exported from Blender; with
// light links (under 20 g), mass ratios over 100 and inertias from meshes.
#include <gtest/gtest.h>

#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/simulation.hpp"
#include "model_files.hpp"
#include "shared_models.hpp"

namespace afhub::physics {
namespace {

const std::string kEcm = AFHUB_SHARED_MODELS "/descriptions/multi-bodies/robots/blender-ecm.yaml";

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}
std::string xyz(const btVector3& v) {
  return "{x: " + number(v.x()) + ", y: " + number(v.y()) + ", z: " + number(v.z()) + "}";
}

double largest_gap(const Simulation& sim) {
  double largest = 0.0;
  for (std::size_t j = 0; j < sim.model().joints.size(); ++j)
    largest = std::max(largest, sim.joint_pivot_gap_m(j));
  return largest;
}

// A joint's index among body `body`'s descendant joints: where its command goes.
std::size_t command_slot(const Model& model, std::size_t body, const std::string& joint) {
  const std::vector<int>& below = model.descendant_joints[body];
  for (std::size_t k = 0; k < below.size(); ++k)
    if (model.joints[below[k]].name == joint) return k;
  ADD_FAILURE() << "no joint " << joint << " below body " << body;
  return 0;
}

// Position sinusoids for some of a body's descendant joints, commanded every step;
// the joints between them get zero effort. Returns the largest pivot gap seen.
struct Sinusoid {
  std::string joint;
  double middle, amplitude, frequency_hz;
};
// `travel`: how far the first target's joint went, end to end.
double run_sinusoids(Simulation& sim, std::size_t body, const std::vector<Sinusoid>& targets,
                     int steps, double* tracking_error = nullptr, double* travel = nullptr) {
  const Model& model = sim.model();
  std::vector<std::size_t> slots;
  BodyInput input;
  for (const Sinusoid& target : targets) {
    slots.push_back(command_slot(model, body, target.joint));
    input.joint_count = std::max<std::uint32_t>(input.joint_count, slots.back() + 1);
  }
  for (std::size_t k = 0; k < slots.size(); ++k) input.joint_modes[slots[k]] = JointMode::kPosition;
  double gap = 0.0, tracking = 0.0;
  double lowest = INFINITY, highest = -INFINITY;
  for (int i = 0; i < steps; ++i) {
    for (std::size_t k = 0; k < slots.size(); ++k) {
      const Sinusoid& t = targets[k];
      input.joint_values[slots[k]] =
          t.middle + t.amplitude * std::sin(2 * M_PI * t.frequency_hz * sim.time_s());
    }
    EXPECT_EQ(sim.input_problem(body, input), nullptr);
    sim.set_input(body, input);
    sim.step();
    gap = std::max(gap, largest_gap(sim));
    const double first = sim.joint_position(model.descendant_joints[body][slots[0]]);
    lowest = std::min(lowest, first);
    highest = std::max(highest, first);
    if (i > steps / 2)  // once the PIDs have caught up
      for (std::size_t k = 0; k < slots.size(); ++k) {
        const int joint = model.descendant_joints[body][slots[k]];
        tracking =
            std::max(tracking, std::abs(sim.joint_position(joint) - input.joint_values[slots[k]]));
      }
  }
  if (tracking_error) *tracking_error = tracking;
  if (travel) *travel = highest - lowest;
  return gap;
}

// An open chain of eight links alternating 2 g and 2 kg (mass ratio 1000), the
// first standing on a fixed base, the rest joined by hinges alternately about y and
// z, falls, swings and twists for two seconds under a gravity that leans it. Solved
// directly (an island of joints, constraint_solver.hpp) every pivot stays within
// about a millimetre; iterated with the world's 20 iterations, as before, they
// opened by 9 cm.
double swinging_chain_gap(bool direct) {
  std::string text = "adf version: '1.0'\nnamespace: /chain/\n";
  text += "gravity: {x: 3.0, y: 2.0, z: -9.81}\nignore inter-collision: true\nbodies: [";
  for (int l = 0; l < 9; ++l) text += (l ? ", BODY l" : "BODY l") + std::to_string(l);
  text += "]\njoints: [";
  for (int l = 1; l < 9; ++l) text += (l > 1 ? ", JOINT j" : "JOINT j") + std::to_string(l);
  text += "]\n";
  for (int l = 0; l < 9; ++l) {
    const char* mass = l == 0 ? "0.0" : l % 2 ? "0.002" : "2.0";
    const char* inertia =
        l % 2 ? "{ix: 2.0e-6, iy: 2.0e-6, iz: 1.0e-6}" : "{ix: 2.0e-3, iy: 2.0e-3, iz: 1.0e-3}";
    text += "BODY l" + std::to_string(l) + ":\n  name: l" + std::to_string(l) +
            "\n  mass: " + mass + "\n  inertia: " + inertia +
            "\n  shape: box\n  geometry: {x: 0.05, y: 0.05, z: 0.1}\n  location:\n"
            "    position: {x: 0.0, y: 0.0, z: " +
            number(0.1 * l) + "}\n";
  }
  for (int l = 1; l < 9; ++l) {
    const std::string axis = l % 2 ? "{x: 0, y: 1, z: 0}" : "{x: 0, y: 0, z: 1}";
    text += "JOINT j" + std::to_string(l) + ":\n  name: j" + std::to_string(l) +
            "\n  parent: BODY l" + std::to_string(l - 1) + "\n  child: BODY l" + std::to_string(l) +
            "\n  type: revolute\n  parent pivot: {x: 0, y: 0, z: 0.05}\n" +
            "  parent axis: " + axis +
            "\n  child pivot: {x: 0, y: 0, z: -0.05}\n  child axis: " + axis + "\n";
  }
  testing::ModelFolder folder;
  Model model = load_adf_files({folder.write("chain.yaml", text)});
  model.world.direct_solve = direct;
  Simulation sim(model, 0.001);
  double gap = 0.0, lowest = INFINITY;
  for (int i = 0; i < 2000; ++i) {
    sim.step();
    gap = std::max(gap, largest_gap(sim));
    lowest = std::min(lowest, sim.body_pose(8).position_m.z);
  }
  EXPECT_TRUE(sim.all_finite());
  EXPECT_LT(lowest, 0.5) << "the chain swings down (its tip starts at 0.8 m)";
  return gap;
}

TEST(OpenChains, ASwingingChainOfLightAndHeavyLinksHoldsItsJointsWhenSolvedDirectly) {
  const double direct = swinging_chain_gap(true), iterated = swinging_chain_gap(false);
  std::printf(
      "swinging chain, mass ratio 1000: largest pivot gap %.4f mm direct, %.4f mm "
      "iterated\n",
      direct * 1e3, iterated * 1e3);
  EXPECT_LT(direct, 0.002);  // 1.2 mm here: a fast fall's drift, pulled back by the ERP
  EXPECT_GT(iterated, 10 * direct) << "the iterated solve is the comparison: it should open";
}

TEST(ClosedLoops, EcmHoldsItsLoopsTenSecondsAtRest) {
  SKIP_WITHOUT_SHARED_MODELS();
  const Model model = load_adf_files({kEcm});
  ASSERT_EQ(model.closed_loop_count, 3);
  Simulation sim(model, 0.001);
  // Its pose as drawn sits inside every joint's limits.
  for (std::size_t j = 0; j < model.joints.size(); ++j)
    if (model.joints[j].limit_low && model.joints[j].type != JointType::kP2P) {
      EXPECT_GE(sim.joint_position(j), *model.joints[j].limit_low - 1e-3) << model.joints[j].name;
      EXPECT_LE(sim.joint_position(j), *model.joints[j].limit_high + 1e-3) << model.joints[j].name;
    }
  double gap = 0.0;
  for (int i = 0; i < 10000; ++i) {
    sim.step();
    gap = std::max(gap, largest_gap(sim));
  }
  std::printf("ECM at rest, 10 s: largest pivot gap %.4f mm\n", gap * 1e3);
  EXPECT_TRUE(sim.all_finite());
  EXPECT_LT(gap, 0.001);
}

// The seed paper's Fig. 9: the ECM's joints (yaw, pitch, insertion, roll) track
// sinusoids commanded in position mode at 1 kHz. Its file gives no joint gains:
// P 1000, D 10 (below the stability cap) make them track within millimetres.
TEST(ClosedLoops, EcmHoldsItsLoopsUnderOneKilohertzSinusoids) {
  SKIP_WITHOUT_SHARED_MODELS();
  Model model = load_adf_files({kEcm});
  for (JointSpec& joint : model.joints) joint.controller = {1000.0, 0.0, 10.0};
  Simulation sim(model, 0.001);
  double tracking = 0.0;
  const double gap = run_sinusoids(sim, 0,
                                   {{"baselink-yawlink", 0.0, 0.5, 0.5},
                                    {"yawlink-pitchbacklink", 0.2, 0.3, 0.4},
                                    {"pitchendlink-maininsertionlink", 0.1, 0.05, 0.3},
                                    {"maininsertionlink-toollink", 0.0, 0.5, 0.6}},
                                   10000, &tracking);
  std::printf("ECM under sinusoids, 10 s: largest pivot gap %.4f mm, tracking error %.4f\n",
              gap * 1e3, tracking);
  EXPECT_TRUE(sim.all_finite());
  EXPECT_LT(gap, 0.001);
  EXPECT_LT(tracking, 0.05);  // they do move as commanded
}

// A slider-crank in the world's xy plane: the crank turns about z at the origin, the
// rod joins it to the slider, the slider moves along x. Every body is placed at an
// arbitrary orientation, and each joint's pivots, axes and `offset` are written in
// the bodies' own frames, as Blender's exporter writes them: the file's pose is
// each joint's zero. With `mirror`, a second rod and slider on the crank's other
// side move with the first (a second loop through a prismatic joint). With a base
// of mass, the base tilts about y on a revolute joint from a fixed `ground`.
struct StressLoop {
  double crank_kg = 0.5, rod_kg = 0.5, slider_kg = 0.5;
  bool mesh_inertia = false;  // each link's inertia from its mesh, not its shape
  double base_kg = 0.0;       // 0: the base is fixed to the world
  bool mirror = false;
  bool gravity = false;  // along -z, out of the loop's plane
};

struct Placed {
  std::string name;
  btTransform pose;
  double mass_kg;
};

std::string stress_loop(const testing::ModelFolder& folder, const StressLoop& loop) {
  const double crank = 0.1, rod = 0.3, angle = M_PI / 3;
  const btVector3 crank_end(crank * std::cos(angle), crank * std::sin(angle), 0);
  const double reach = std::sqrt(rod * rod - crank_end.y() * crank_end.y());
  const btVector3 slider(crank_end.x() + reach, 0, 0), mirror(crank_end.x() - reach, 0, 0);
  auto pose = [](double r, double p, double y, const btVector3& at) {
    btQuaternion q;
    q.setEulerZYX(y, p, r);
    return btTransform(q, at);
  };
  std::vector<Placed> bodies = {
      {"base", pose(0.3, -1.2, 2.0, btVector3(0, 0, 0)), loop.base_kg},
      {"crank", pose(1.9, 0.4, -2.6, crank_end * 0.5), loop.crank_kg},
      {"rod", pose(-2.3, 1.1, 0.7, (crank_end + slider) * 0.5), loop.rod_kg},
      {"slider", pose(2.8, -0.5, 1.3, slider), loop.slider_kg},
  };
  if (loop.mirror) {
    bodies.push_back({"mirror rod", pose(1.2, 2.1, -0.4, (crank_end + mirror) * 0.5), loop.rod_kg});
    bodies.push_back({"mirror slider", pose(-0.9, 0.2, 2.4, mirror), loop.slider_kg});
  }
  if (loop.base_kg > 0) bodies.push_back({"ground", pose(0.7, 0.3, -1.1, btVector3(0, 0, 0)), 0.0});
  std::string names, text;
  for (const Placed& body : bodies) names += (names.empty() ? "BODY " : ", BODY ") + body.name;
  text = "bodies: [" + names + "]\njoints: [";
  if (loop.mesh_inertia) {
    // A 4 x 2 x 1 cm box, centred on its origin.
    folder.write("link.obj",
                 "v -0.02 -0.01 -0.005\nv 0.02 -0.01 -0.005\nv 0.02 0.01 -0.005\n"
                 "v -0.02 0.01 -0.005\nv -0.02 -0.01 0.005\nv 0.02 -0.01 0.005\n"
                 "v 0.02 0.01 0.005\nv -0.02 0.01 0.005\n"
                 "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
                 "f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n");
  }
  std::string body_text;
  for (const Placed& body : bodies) {
    btScalar y, p, r;
    body.pose.getBasis().getEulerZYX(y, p, r);
    body_text += "BODY " + body.name + ":\n  name: " + body.name +
                 "\n  mass: " + number(body.mass_kg) +
                 "\n  location: {position: " + xyz(body.pose.getOrigin()) +
                 ", orientation: {r: " + number(r) + ", p: " + number(p) + ", y: " + number(y) +
                 "}}\n" + "  damping: {linear: 0, angular: 0}\n";
    if (body.mass_kg == 0) continue;
    if (loop.mesh_inertia)
      body_text += "  mesh: link.obj\n  inertial offset: {position: {x: 0, y: 0, z: 0}}\n";
    else
      body_text += "  shape: box\n  geometry: {x: 0.04, y: 0.02, z: 0.01}\n";
  }
  auto index = [&](const std::string& name) {
    for (std::size_t b = 0; b < bodies.size(); ++b)
      if (bodies[b].name == name) return b;
    ADD_FAILURE() << "no body " << name;
    return std::size_t{0};
  };
  // The world point and axis of each joint, written in each of its bodies' frames.
  std::string joint_names, joint_text;
  auto joint = [&](const std::string& parent_name, const std::string& child_name,
                   const btVector3& at, const btVector3& axis, const std::string& type,
                   const std::string& limits, bool passive) {
    const std::string name = parent_name + "-" + child_name;
    joint_names += (joint_names.empty() ? "JOINT " : ", JOINT ") + name;
    const Placed& parent = bodies[index(parent_name)];
    const Placed& child = bodies[index(child_name)];
    const btTransform& p = parent.pose;
    const btTransform& c = child.pose;
    const btVector3 parent_axis = p.getBasis().transpose() * axis;
    const btVector3 child_axis = c.getBasis().transpose() * axis;
    // The child's turn about the axis beyond the short turn of its axis onto the
    // parent's: the exporter's `offset`.
    const btQuaternion relative = p.getRotation().inverse() * c.getRotation();
    const btQuaternion twist =
        relative * shortestArcQuat(child_axis.normalized(), parent_axis.normalized()).inverse();
    const double offset =
        2 * std::atan2(btVector3(twist.x(), twist.y(), twist.z()).dot(parent_axis), twist.w());
    joint_text += "JOINT " + name + ":\n  name: " + name + "\n  parent: BODY " + parent.name +
                  "\n  child: BODY " + child.name + "\n  parent pivot: " + xyz(p.invXform(at)) +
                  "\n  parent axis: " + xyz(parent_axis) +
                  "\n  child pivot: " + xyz(c.invXform(at)) + "\n  child axis: " + xyz(child_axis) +
                  "\n  offset: " + number(offset) + "\n  type: " + type +
                  "\n  joint limits: " + limits + "\n  max motor impulse: 1\n" +
                  (passive ? "  passive: true\n" : "") +
                  // Gains that track a 1 Hz sinusoid: the D term acts on the measured
                  // velocity, so the default P 10, D 1 lags by about D v / P, 0.25 rad
                  // at its peak speed.
                  "  controller: {P: 200, I: 0, D: 2}\n";
  };
  const btVector3 x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  const std::string turn = "{low: -1.2, high: 1.2}", slide = "{low: -0.1, high: 0.1}";
  if (loop.base_kg > 0) joint("ground", "base", btVector3(0, 0, 0), y, "revolute", turn, false);
  joint("base", "crank", btVector3(0, 0, 0), z, "revolute", turn, false);
  joint("crank", "rod", crank_end, z, "revolute", turn, true);
  joint("rod", "slider", slider, z, "revolute", turn, true);
  joint("base", "slider", slider, x, "prismatic", slide, false);
  if (loop.mirror) {
    joint("crank", "mirror rod", crank_end, z, "revolute", turn, true);
    joint("mirror rod", "mirror slider", mirror, z, "revolute", turn, true);
    joint("base", "mirror slider", mirror, x, "prismatic", slide, true);
  }
  text += joint_names + "]\n" +
          (loop.gravity ? "gravity: {x: 0, y: 0, z: -9.81}\n" : "gravity: {x: 0, y: 0, z: 0}\n") +
          "ignore inter-collision: true\n" + body_text + joint_text;
  return folder.write("stress_loop.yaml", text);
}

// The cause of the ECM's open loop, on a model of our own: a joint whose axes differ
// between parent, child and Bullet's constraint axis read its zero from an arbitrary
// direction, so the pose as drawn started outside the joint limits (pi away on the
// ECM's yaw) and the limits threw the links apart.
TEST(ClosedLoops, ArbitrarilyOrientedSliderCrankStartsAtZeroAndHolds) {
  testing::ModelFolder folder;
  const Model model = load_adf_files({stress_loop(folder, {})});
  ASSERT_EQ(model.closed_loop_count, 1);
  Simulation sim(model, 0.001);
  for (std::size_t j = 0; j < model.joints.size(); ++j)
    EXPECT_NEAR(sim.joint_position(j), 0.0, 1e-6) << model.joints[j].name;
  double gap = 0.0;
  for (int i = 0; i < 10000; ++i) {
    sim.step();
    gap = std::max(gap, largest_gap(sim));
  }
  EXPECT_LT(gap, 0.001) << "at rest";
  for (std::size_t j = 0; j < model.joints.size(); ++j)
    EXPECT_NEAR(sim.joint_position(j), 0.0, 1e-3) << model.joints[j].name;
  double tracking = 0.0;
  gap = run_sinusoids(sim, 0, {{"base-crank", 0.0, 0.4, 1.0}}, 5000, &tracking);
  EXPECT_LT(gap, 0.001) << "under 1 kHz sinusoid commands";
  EXPECT_LT(tracking, 0.05);
  EXPECT_EQ(sim.nan_recoveries().count, 0u);
}

// The class of robot that fell apart (issue 31): closed loops through prismatic
// joints, passive loop joints, mass ratios over a thousand, 2 g links on 6 kg
// bodies, inertias from meshes, gravity across the loop's plane. Each holds its
// loops within 1 mm at rest, and while its slider (and its base, when it tilts)
// follow 1 Hz sinusoids; no body goes NaN.
TEST(ClosedLoops, StressCorpusHoldsItsLoopsWithinAMillimetre) {
  const std::vector<std::pair<std::string, StressLoop>> corpus = {
      {"light links", {.crank_kg = 0.01, .rod_kg = 0.015, .slider_kg = 0.008}},
      {"mass ratio 500", {.crank_kg = 0.01, .rod_kg = 5.0, .slider_kg = 0.012}},
      {"mass ratio 400, mesh inertia",
       {.crank_kg = 2.0, .rod_kg = 0.005, .slider_kg = 0.015, .mesh_inertia = true}},
      {"2 g links, 6 kg sliders, two loops, gravity",
       {.crank_kg = 0.002, .rod_kg = 0.002, .slider_kg = 6.0, .mirror = true, .gravity = true}},
      {"2 g links on a 6.6 kg tilting base, mesh inertia, two loops, gravity",
       {.crank_kg = 0.002,
        .rod_kg = 0.003,
        .slider_kg = 0.5,
        .mesh_inertia = true,
        .base_kg = 6.6,
        .mirror = true,
        .gravity = true}},
      {"6 kg crank, 1.2 g rods, 2 g sliders, mesh inertia, two loops, gravity",
       {.crank_kg = 6.0,
        .rod_kg = 0.0012,
        .slider_kg = 0.002,
        .mesh_inertia = true,
        .mirror = true,
        .gravity = true}},
  };
  for (const auto& [name, loop] : corpus) {
    testing::ModelFolder folder;
    const Model model = load_adf_files({stress_loop(folder, loop)});
    ASSERT_EQ(model.closed_loop_count, loop.mirror ? 2 : 1) << name;
    Simulation sim(model, 0.001);
    double rest = 0.0;
    for (int i = 0; i < 5000; ++i) {
      sim.step();
      rest = std::max(rest, largest_gap(sim));
    }
    std::vector<Sinusoid> drive = {{"base-slider", 0.0, 0.02, 1.0}};
    std::size_t commanding = 0;  // the base, or the ground its base turns on
    if (loop.base_kg > 0) {
      drive.push_back({"ground-base", 0.0, 0.3, 0.5});
      commanding = model.bodies.size() - 1;
    }
    double travel = 0.0;
    const double driven = run_sinusoids(sim, commanding, drive, 5000, nullptr, &travel);
    std::printf("%s: largest pivot gap %.4f mm at rest, %.4f mm driven (slider travel %.1f mm)\n",
                name.c_str(), rest * 1e3, driven * 1e3, travel * 1e3);
    EXPECT_TRUE(sim.all_finite()) << name;
    EXPECT_EQ(sim.nan_recoveries().count, 0u) << name;
    EXPECT_LT(rest, 0.001) << name << ", at rest";
    EXPECT_LT(driven, 0.001) << name << ", driven";
    EXPECT_GT(travel, 0.02) << name << ": the slider moves (commanded 40 mm end to end)";
  }
}

// Contacts inside a loop's island: a 0.5 kg plate (a file of its own, so that it
// collides with the loop) falls on a loop of 2 g links and lies across them and two
// fixed posts. Contacts and friction are solved with the joints; the loop holds
// within 1 mm.
TEST(ClosedLoops, APlateLyingOnALoopOfTwoGramLinksKeepsItShut) {
  testing::ModelFolder folder;
  const StressLoop loop{.crank_kg = 0.002, .rod_kg = 0.002, .slider_kg = 0.002, .gravity = true};
  const std::string loop_file = stress_loop(folder, loop);
  auto box = [](const std::string& name, double kg, const std::string& size,
                const std::string& at) {
    return "BODY " + name + ":\n  name: " + name + "\n  mass: " + number(kg) +
           "\n  shape: box\n  geometry: " + size + "\n  location: {position: " + at +
           ", orientation: {r: 0, p: 0, y: 0}}\n";
  };
  const std::string plate_file = folder.write(
      "plate.yaml",
      "bodies: [BODY plate, BODY post 1, BODY post 2]\njoints: []\n" +
          box("plate", 0.5, "{x: 0.5, y: 0.3, z: 0.01}", "{x: 0.15, y: 0.06, z: 0.05}") +
          box("post 1", 0, "{x: 0.02, y: 0.02, z: 0.02}", "{x: -0.05, y: 0.18, z: 0.005}") +
          box("post 2", 0, "{x: 0.02, y: 0.02, z: 0.02}", "{x: 0.35, y: 0.18, z: 0.005}"));
  const Model model = load_adf_files({loop_file, plate_file});
  Simulation sim(model, 0.001);
  double gap = 0.0;
  std::uint32_t touching_steps = 0;
  for (int i = 0; i < 3000; ++i) {
    sim.step();
    gap = std::max(gap, largest_gap(sim));
    bool touching = false;
    for (std::size_t link = 1; link <= 3; ++link) {  // crank, rod, slider
      BodyReading reading;
      sim.read_body(link, reading);
      touching |= reading.contact_count > 0;
    }
    touching_steps += touching;
  }
  std::printf("plate on the loop: %u of 3000 steps touching it, largest pivot gap %.4f mm\n",
              touching_steps, gap * 1e3);
  EXPECT_GT(touching_steps, 2000u);
  EXPECT_TRUE(sim.all_finite());
  EXPECT_LT(gap, 0.001);
}

// Whatever makes a body NaN (here a NaN force, as a caller skipping input_problem
// would give): the step puts it back at its pose before that step, at rest, counts
// it, names it and the step, and releases its commands; the world goes on.
TEST(ClosedLoops, ANanBodyIsPutBackAndTheWorldGoesOn) {
  testing::ModelFolder folder;
  const Model model =
      load_adf_files({stress_loop(folder, {.crank_kg = 0.01, .rod_kg = 2.0, .slider_kg = 0.01})});
  Simulation sim(model, 0.001);
  run_sinusoids(sim, 0, {{"base-crank", 0.0, 0.3, 1.0}}, 300);
  const std::size_t crank = 1;
  ASSERT_EQ(model.bodies[crank].name, "crank");
  ASSERT_EQ(sim.joint_driver(0), 0);  // the base drives base-crank
  const Pose before = sim.body_pose(crank);
  BodyInput poison;
  poison.wrench.force_n = {std::nan(""), 0, 0};
  ASSERT_NE(sim.input_problem(crank, poison), nullptr);  // refused when checked
  sim.set_input(crank, poison);
  sim.step();
  ASSERT_TRUE(sim.all_finite());
  const NanRecoveries& nan = sim.nan_recoveries();
  ASSERT_GE(nan.count, 1u);
  EXPECT_EQ(nan.first.step, 301u);
  EXPECT_FALSE(nan.first.soft);
  bool crank_named = false;  // its neighbours may go NaN in the same step
  for (const NanEvent& event : {nan.first, nan.last}) crank_named |= event.body == crank;
  EXPECT_TRUE(crank_named);
  const Pose after = sim.body_pose(crank);
  EXPECT_NEAR(after.position_m.x, before.position_m.x, 1e-12);
  EXPECT_NEAR(after.position_m.y, before.position_m.y, 1e-12);
  EXPECT_NEAR(after.position_m.z, before.position_m.z, 1e-12);
  BodyReading reading;
  sim.read_body(crank, reading);
  EXPECT_EQ(reading.twist.linear_mps.x, 0.0);
  // The crank's commands, and the joints touching it, are released.
  EXPECT_EQ(sim.joint_driver(0), -1);
  // The world goes on, its loop holding, and takes commands again.
  const std::uint64_t recovered = nan.count;
  const double gap = run_sinusoids(sim, 0, {{"base-crank", 0.0, 0.3, 1.0}}, 2000);
  EXPECT_TRUE(sim.all_finite());
  EXPECT_LT(gap, 0.005);  // a mass ratio of 200 (see StressLoopsNeverEndTheWorld)
  EXPECT_EQ(sim.nan_recoveries().count, recovered);
}

}  // namespace
}  // namespace afhub::physics
