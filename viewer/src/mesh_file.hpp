// The one kind of file /mesh/N reads from the disk: the N-th mesh a scene lists, when it
// is a regular file (no symlink at the moment it is opened), with a mesh format's
// extension, within a model folder the scene lists. Any member of the hub's group can
// publish a scene, so the scene's paths are not trusted to name only meshes.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "afhub/viewer/view_scene.hpp"

namespace afhub::viewer {

// The extensions served, any case: formats the physics reads meshes in (assimp's
// common ones) and the page draws or may draw.
bool is_mesh_extension(std::string_view path);

class MeshFile {
 public:
  // Opens the scene's mesh number `index_text` ("3"); check problem().
  MeshFile(const ViewScene& scene, std::string_view index_text);
  ~MeshFile();
  MeshFile(const MeshFile&) = delete;
  MeshFile& operator=(const MeshFile&) = delete;

  // "" when open; else why not, for the reply, with status() its HTTP status.
  const std::string& problem() const { return problem_; }
  int status() const { return status_; }
  int fd() const { return fd_; }
  std::size_t size() const { return size_; }

 private:
  void open(const ViewScene& scene, std::string_view index_text);
  void refuse(int status, std::string problem);

  int fd_ = -1;
  std::size_t size_ = 0;
  int status_ = 200;
  std::string problem_;
};

}  // namespace afhub::viewer
