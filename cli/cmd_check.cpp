// `afhub check FILES...`: loads AMBF descriptions without simulating and reports
// bodies, joints by type, closed loops, total mass and warnings. It reads every
// mesh too, so that what `afhub run` would refuse is refused here.
#include <cstdio>
#include <map>
#include <memory>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/mesh.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"

namespace afhub::cli {
namespace {

struct CheckOptions {
  std::vector<std::string> files;
};

int run_check(const CheckOptions& options) {
  physics::Model model;
  std::size_t meshes = 0;
  try {
    model = physics::load_adf_files(options.files);
    // The meshes too: `afhub run` reads them, and a broken one must show here first.
    meshes = physics::check_meshes(model);
  } catch (const Error& error) {
    std::fprintf(stderr, "%s\n", error.what());  // already "file:line:col: error: ..."
    return 1;
  }
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
  std::printf("meshes read: %zu\n", meshes);
  std::printf("warnings: %zu\n", model.warnings.size());
  return 0;
}

}  // namespace

void register_check(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<CheckOptions>();
  auto* check = app.add_subcommand(
      "check",
      "Validate AMBF description files without simulating: bodies, joints, loops, mass, warnings.");
  check->add_option("files", options->files, "ADF files, loaded together")->required();
  check->callback([&selected, options] { selected = [options] { return run_check(*options); }; });
}

}  // namespace afhub::cli
