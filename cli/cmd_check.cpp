// `afhub check FILES...`: loads AMBF descriptions without simulating and reports
// bodies, joints by type, closed loops, total mass, the effective gravity, the
// joints left on AMBF's default gains, joint gains the stability cap lowers, and
// warnings. It reads every mesh too, so that
// what `afhub run` would refuse is refused here.
#include <cstdio>
#include <map>
#include <memory>

#include "afhub/physics/mesh.hpp"
#include "afhub/physics/scene_loader.hpp"
#include "afhub/physics/simulation.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"
#include "format.hpp"
#include "gain_options.hpp"
#include "scene_options.hpp"

namespace afhub::cli {
namespace {

struct CheckOptions {
  SceneOptions scene;
  std::string gravity;
  double dt_s = 0.001;
  GainOptions gains;
};

std::string vec3_text(const Vec3& v) {
  char text[96];
  std::snprintf(text, sizeof text, "(%g, %g, %g)", v.x, v.y, v.z);
  return text;
}

// The gravity each body falls under, by AMBF's rule (a body's or its file's gravity
// over the world's), grouped.
void print_gravity(const physics::Model& model, const std::string& source) {
  std::printf("gravity: world %s m/s^2 (%s)\n", vec3_text(model.world.gravity_mps2).c_str(),
              source.c_str());
  std::map<std::string, int> own;
  for (const auto& body : model.bodies)
    if (body.gravity_mps2) ++own[vec3_text(*body.gravity_mps2)];
  for (const auto& [gravity, count] : own)
    std::printf(
        "  %d bodies fall under %s m/s^2: their file's or their own `gravity`, which "
        "wins over the world's (--gravity overrides both)\n",
        count, gravity.c_str());
}

// The joints a position command can drive whose file gives no `controller`: they
// take AMBF's default gains, which barely move a real arm.
void print_default_gains(const physics::Model& model) {
  std::vector<const physics::JointSpec*> defaulted;
  for (const auto& joint : model.joints)
    if (joint.gains_from == physics::GainSource::kAmbfDefault && !joint.passive &&
        physics::has_joint_axis(joint.type))
      defaulted.push_back(&joint);
  std::printf(
      "joints on AMBF's default gains (P 10, I 0, D 1: their file gives no `controller`; "
      "`afhub run --default-gains P,I,D` sets theirs): %zu\n",
      defaulted.size());
  for (const auto* joint : defaulted)
    std::printf("  %-40s %s\n", joint->channel.c_str(), joint->where.str().c_str());
}

int run_check(const CheckOptions& options) {
  if (!(options.dt_s >= 1e-5 && options.dt_s <= 0.1))
    throw Error("--dt must be between 0.00001 and 0.1 s, got " + std::to_string(options.dt_s));
  physics::Model model;
  std::size_t meshes = 0;
  try {
    model = physics::load_scene(scene_request(options.scene));
    // The meshes too: `afhub run` reads them, and a broken one must show here first.
    meshes = physics::check_meshes(model);
  } catch (const Error& error) {
    std::fprintf(stderr, "%s\n", error.what());  // already "file:line:col: error: ..."
    return 1;
  }
  const std::string& world_file = options.scene.world_file;
  std::string gravity_source = world_file.empty() ? "default" : world_file;
  if (!options.gravity.empty()) {
    physics::override_gravity(model, parse_gravity(options.gravity, model.warnings));
    gravity_source = "--gravity";
  }
  apply_gain_options(model, options.gains);  // refused before the report, as gravity
  for (const auto& warning : model.warnings) std::fprintf(stderr, "%s\n", warning.c_str());
  double total_mass = 0.0;
  for (const auto& body : model.bodies) total_mass += body.mass_kg;
  std::map<std::string, int> by_type;
  for (const auto& joint : model.joints) ++by_type[physics::joint_type_name(joint.type)];
  std::printf("bodies: %zu (total mass %.3f kg)\n", model.bodies.size(), total_mass);
  for (std::size_t i = 0; i < model.bodies.size(); ++i)
    std::printf("  %-40s %8.3f kg  %zu joints below\n", model.bodies[i].channel.c_str(),
                model.bodies[i].mass_kg, model.descendant_joints[i].size());
  std::printf("joints: %zu\n", model.joints.size());
  for (const auto& [type, count] : by_type) std::printf("  %-16s %d\n", type.c_str(), count);
  std::printf("closed loops: %d\n", model.closed_loop_count);
  for (const std::string& note : model.notes) std::printf("%s\n", note.c_str());
  std::printf("meshes read: %zu\n", meshes);
  print_gravity(model, gravity_source);
  print_default_gains(model);
  // The gains in use need the bodies' inertias, the overlaps their shapes: the world is
  // built, not stepped.
  std::vector<std::string> built_warnings;
  try {
    const physics::Simulation sim(model, options.dt_s);
    for (const std::string& note : sim.parted_overlaps()) std::printf("%s\n", note.c_str());
    const std::vector<std::string> notes = sim.gain_notes();
    std::printf("joint gains lowered for stability at dt %g s: %zu\n", options.dt_s, notes.size());
    for (const std::string& note : notes) std::printf("  %s\n", note.c_str());
    built_warnings = sim.overlaps_between_files();
    for (const std::string& warning : sim.joints_outside_limits())
      built_warnings.push_back(warning);
    std::fflush(stdout);  // its lines whole before these on stderr (`check ... > log 2>&1`)
    for (const std::string& warning : built_warnings) std::fprintf(stderr, "%s\n", warning.c_str());
  } catch (const Error& error) {
    std::fprintf(stderr, "%s\n", error.what());  // a mesh that cannot be read
    return 1;
  }
  std::printf("warnings: %zu\n", model.warnings.size() + built_warnings.size());
  return 0;
}

}  // namespace

void register_check(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<CheckOptions>();
  auto* check = app.add_subcommand(
      "check",
      "Validate AMBF description files without simulating: bodies, joints, loops, mass, warnings.");
  add_scene_options(check, options->scene, "A world file (its gravity, as `afhub run`)");
  check->add_option("--gravity", options->gravity,
                    "x,y,z in m/s^2: the gravity `afhub run --gravity` would use");
  check->add_option("--dt", options->dt_s,
                    "The step the joint gains are checked for (default 0.001 s, as `afhub run`)");
  add_gain_options(check, options->gains);
  check->callback([&selected, options] { selected = [options] { return run_check(*options); }; });
}

}  // namespace afhub::cli
