// `afhub convert robot.urdf -o robot.yaml`: a URDF robot as an ADF file that `afhub
// run` loads to the same bodies, joints and poses, for a user to add what URDF cannot
// say (closed loops, soft bodies, sensors, actuators).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/adf_writer.hpp"
#include "afhub/physics/mesh.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"
#include "urdf_options.hpp"

namespace afhub::cli {
namespace {

struct ConvertOptions {
  std::string urdf_file, output_file;
  physics::UrdfOptions urdf;
};

int run_convert(const ConvertOptions& options) {
  if (!physics::is_urdf_path(options.urdf_file))
    throw Error("'" + options.urdf_file + "' is not a .urdf file; afhub convert reads URDF");
  // The same file by another name (or a link to it) would be overwritten by its own ADF.
  std::error_code same_error;
  if (std::filesystem::equivalent(options.urdf_file, options.output_file, same_error))
    throw Error("-o " + options.output_file +
                " is the URDF file itself; write the ADF beside "
                "it, e.g. -o " +
                std::filesystem::path(options.urdf_file).replace_extension(".yaml").string());
  physics::Model model;
  try {
    physics::load_adf_files_into({options.urdf_file}, model, options.urdf);
    // What convert writes, `afhub run` loads: a mesh it cannot read is refused here.
    physics::check_meshes(model);
  } catch (const Error& error) {
    std::fprintf(stderr, "%s\n", error.what());
    return 1;
  }
  for (const auto& warning : model.warnings) std::fprintf(stderr, "%s\n", warning.c_str());
  std::vector<std::string> lost;
  const std::string text = physics::adf_text(model, lost);
  for (const auto& what : lost) std::fprintf(stderr, "afhub convert: warning: %s\n", what.c_str());
  std::ofstream out(options.output_file);
  out << text;
  out.close();
  if (!out) throw Error("cannot write " + options.output_file);
  std::fprintf(stderr, "afhub convert: %zu bodies, %zu joints written to %s\n", model.bodies.size(),
               model.joints.size(), options.output_file.c_str());
  return 0;
}

}  // namespace

void register_convert(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<ConvertOptions>();
  auto* convert = app.add_subcommand(
      "convert", "Write a URDF robot as an ADF file that `afhub run` loads to the same robot.");
  convert->add_option("urdf", options->urdf_file, "The URDF file")->required();
  convert->add_option("-o,--output", options->output_file, "The ADF file to write")->required();
  add_urdf_options(convert, options->urdf);
  convert->callback(
      [&selected, options] { selected = [options] { return run_convert(*options); }; });
}

}  // namespace afhub::cli
