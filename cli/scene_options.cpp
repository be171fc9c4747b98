// See scene_options.hpp.
#include "scene_options.hpp"

#include "format.hpp"
#include "placement_option.hpp"
#include "urdf_options.hpp"

namespace afhub::cli {

void add_scene_options(CLI::App* command, SceneOptions& options, const std::string& world_help) {
  command->add_option("files", options.files, "ADF and URDF files, loaded together");
  command->add_option("--launch", options.launch_file,
                      "A launch file: its world config, colors, and the models picked with -l");
  // One value each (repeated -l adds more): a list of values would take the files after.
  command
      ->add_option("-l", options.indices,
                   "Indices into the launch file's multibody configs: 0,3 (or -l 0 -l 3)")
      ->allow_extra_args(false);
  command
      ->add_option("-a", options.adf_lists,
                   "ADF files, comma-separated: a.yaml,b.yaml (or -a a.yaml -a b.yaml)")
      ->allow_extra_args(false);
  command->add_option("--world", options.world_file, world_help);
  add_placement_option(command, options.placements);
  add_urdf_options(command, options.urdf);
}

physics::SceneRequest scene_request(const SceneOptions& options) {
  physics::SceneRequest request;
  request.launch_file = options.launch_file;
  for (const std::string& list : options.indices)
    for (const int index : physics::parse_index_list(list)) request.launch_indices.push_back(index);
  for (const std::string& list : options.adf_lists)
    for (const std::string& file : split_commas(list)) request.adf_files.push_back(file);
  request.adf_files.insert(request.adf_files.end(), options.files.begin(), options.files.end());
  request.world_file = options.world_file;
  request.urdf = options.urdf;
  for (const std::string& placement : options.placements)
    request.placements.push_back(physics::parse_file_placement(placement));
  return request;
}

}  // namespace afhub::cli
