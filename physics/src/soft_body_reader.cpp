// ADF soft bodies (SOFTBODY blocks): mass, placement, the mesh, and Bullet's
// btSoftBody config by its ADF names, with fixed nodes, bending and clusters.
#include <cctype>
#include <cmath>

#include "adf_blocks.hpp"
#include "afhub/shm_layout/channel_names.hpp"

namespace afhub::physics::adf {
namespace {

const std::set<std::string> kSoftBodyKeys = {"name",
                                             "namespace",
                                             "mesh",
                                             "mass",
                                             "location",
                                             "scale",
                                             "config",
                                             "high resolution path",
                                             "low resolution path",
                                             "color",
                                             "color rgba",
                                             "color components",
                                             "collision margin",
                                             "randomize constraints",
                                             "publish frequency",
                                             "plugins"};

// Counts that size Bullet's work (iterations, clusters, links): large ones would
// make each step take hours.
constexpr double kMaxSoftBodyCount = 1000;

int count(const FileReader& file, const YAML::Node& node, const std::string& what) {
  const double value = file.non_negative(node, what);
  if (value != std::floor(value) || value > kMaxSoftBodyCount)
    fail(file.at(node), "'" + what + "' must be an integer from 0 to " +
                            yaml::number_text(kMaxSoftBodyCount) + ", got " + node.Scalar());
  return static_cast<int>(value);
}

}  // namespace

SoftBodySpec read_soft_body(const FileReader& file, const YAML::Node& block,
                            const std::string& identifier, const FileContext& context) {
  SoftBodySpec soft;
  read_block_head(file, block, identifier, kSoftBodyKeys, "soft body", soft);
  std::erase(soft.name, ' ');
  const std::string name_space = block_namespace(file, block, context);
  soft.channel = body_channel_name(name_space, soft.name);
  const YAML::Node mass = file.require(block, "mass", soft.where);
  soft.mass_kg = positive(file, mass, "mass");
  if (soft.mass_kg > kMaxMassKg)
    fail(file.at(mass), "'mass' is " + mass.Scalar() + " kg, beyond the bound of " +
                            yaml::number_text(kMaxMassKg) + " kg for a model");
  if (soft.mass_kg < kMinMovingMassKg)
    fail(file.at(mass), "'mass' is " + mass.Scalar() + " kg, below the " +
                            yaml::number_text(kMinMovingMassKg) +
                            " kg a moving body needs (Bullet divides by it)");
  if (YAML::Node location = block["location"]) soft.location = file.placement(location, "location");
  if (YAML::Node scale = block["scale"]) {
    positive(file, scale, "scale");
    soft.scale = file.bounded(scale, "scale", kMaxScale, "(a factor)");
  }
  std::string high = context.high_res_folder;
  if (YAML::Node h = block["high resolution path"]) high = mesh_folder(file, h, context.dir);
  soft.mesh = resolve_mesh(file, file.require(block, "mesh", soft.where), high, "mesh");
  if (YAML::Node config = block["config"]) {
    file.require_map(config, "config", "{kLST: 0.5, piterations: 10, fixed nodes: [0, 1]}");
    for (const auto& entry : config) {
      const std::string key = entry.first.Scalar();
      if (key == "fixed nodes") {
        if (!entry.second.IsSequence())
          fail(file.at(entry.second), "'config.fixed nodes' must be a list of node indices");
        for (const auto& node : entry.second) {
          const double index = file.non_negative(node, "config.fixed nodes entry");
          if (index != std::floor(index))
            fail(file.at(node), "'config.fixed nodes' entries are node indices (integers)");
          soft.fixed_nodes.push_back(static_cast<int>(index));
        }
      } else if (key == "bending constraint") {
        soft.bending_constraint = count(file, entry.second, "config.bending constraint");
      } else if (key == "clusters") {
        soft.clusters = count(file, entry.second, "config.clusters");
      } else if (key.ends_with("iterations")) {
        soft.config.emplace_back(key, count(file, entry.second, "config." + key));
      } else if (entry.second.IsScalar()) {
        bool flag_value = false;
        if (YAML::convert<bool>::decode(entry.second, flag_value) &&
            !std::isdigit(static_cast<unsigned char>(entry.second.Scalar()[0])))
          soft.config.emplace_back(key, flag_value ? 1.0 : 0.0);
        else
          soft.config.emplace_back(key, file.number(entry.second, "config." + key));
      } else {
        file.warn(entry.first, "soft body config '" + key + "' is not a value and is ignored");
      }
    }
  }
  return soft;
}

}  // namespace afhub::physics::adf
