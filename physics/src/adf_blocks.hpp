// The ADF loader's block readers (one file per kind of block, beside its table of
// known keys) and what they share: the file's context, a block's head, meshes,
// shapes, PID gains. Internal to the loader (see adf_loader.hpp).
#pragma once

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "afhub/physics/model.hpp"
#include "body_scope.hpp"
#include "file_reader.hpp"

namespace afhub::physics::adf {

// What a file says for every block in it: namespace, mesh folders, gravity.
struct FileContext {
  std::string name_space;
  std::string high_res_folder, low_res_folder;
  std::optional<Vec3> gravity;
  std::filesystem::path dir;
  int file_index = 0;
};

// A joint whose parent and child are still identifiers (resolved across files later).
struct PendingJoint {
  JointSpec spec;
  std::string parent, child;
  SourceLocation parent_at, child_at;
  Referrer from;  // the joint's file and namespace, where its names are looked up first
};

// A sensor's or actuator's parent, resolved once every file is loaded.
struct PendingParent {
  bool sensor = true;
  std::size_t index = 0;
  std::string parent;
  SourceLocation parent_at;
  Referrer from;
};

// What every block starts with: where it is, that it is a map, its keys, its name.
template <class Spec>
void read_block_head(const FileReader& file, const YAML::Node& block, const std::string& identifier,
                     const std::set<std::string>& keys, const char* kind, Spec& spec) {
  spec.identifier = identifier;
  spec.where = file.at(block);
  if (!block.IsMap()) fail(spec.where, "'" + identifier + "' must be a map of " + kind + " keys");
  file.check_keys(block, keys, identifier);
  spec.name = file.text(file.require(block, "name", spec.where), "name");
}

// Shared by the readers (adf_loader.cpp).
// The block's `namespace`, inside the file's.
std::string block_namespace(const FileReader& file, const YAML::Node& block,
                            const FileContext& context);
// A mesh file named at `node`, looked for in `folder`; must exist.
std::string resolve_mesh(const FileReader& file, const YAML::Node& node, const std::string& folder,
                         const std::string& what);
// A resolution path key (file or body level), relative to the file's folder.
std::string mesh_folder(const FileReader& file, const YAML::Node& value,
                        const std::filesystem::path& file_dir);
double positive(const FileReader& file, const YAML::Node& node, const std::string& what);
Pid read_pid(const FileReader& file, const YAML::Node& node, const std::string& what);
ControllerOutput read_output_type(const FileReader& file, const YAML::Node& node);
// A sensor's or actuator's `parent`, kept for resolving later.
void read_parent(const FileReader& file, const YAML::Node& block, const SourceLocation& where,
                 PendingParent& pending);

// Primitive shapes (shape_reader.cpp).
// `kind_node` is the shape's name, `geometry` its sizes; `owner` is the block, for
// the location of a missing geometry.
ShapeSpec read_shape(const FileReader& file, const YAML::Node& kind_node,
                     const YAML::Node& geometry, const std::string& what, const YAML::Node& owner);
std::vector<ShapeSpec> read_compound(const FileReader& file, const YAML::Node& list,
                                     const std::string& what);
// `scale` applies to primitives as it does to meshes: sizes and offsets.
void scale_shapes(std::vector<ShapeSpec>& shapes, double scale);

// The whole model's checks (model_checks.cpp): unique and unreserved channels, and
// the per-body capacities of the hub's payloads.
void check_model(const Model& model);
// Refuses a model of more than kMaxModelBodies bodies with `count` listed so far,
// `where` being the first of those a file lists, before any of them is read.
void count_model_bodies(std::size_t count, const SourceLocation& where);
// Counts a body that publishes; refuses the one past the hub's kMaxBodies.
void count_published_body(const std::string& identifier, const SourceLocation& where,
                          std::size_t& published);

// The block readers, one per file.
BodySpec read_body(const FileReader& file, const YAML::Node& block, const std::string& identifier,
                   const FileContext& context);
PendingJoint read_joint(const FileReader& file, const YAML::Node& block,
                        const std::string& identifier, const FileContext& context);
SoftBodySpec read_soft_body(const FileReader& file, const YAML::Node& block,
                            const std::string& identifier, const FileContext& context);
SensorSpec read_sensor(const FileReader& file, const YAML::Node& block,
                       const std::string& identifier, PendingParent& pending);
ActuatorSpec read_actuator(const FileReader& file, const YAML::Node& block,
                           const std::string& identifier, PendingParent& pending);

}  // namespace afhub::physics::adf
