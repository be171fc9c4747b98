// A scene body's mesh file, opened for serving (see mesh_file.hpp).
#include "mesh_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <filesystem>
#include <optional>

namespace afhub::viewer {
namespace {

constexpr std::array<std::string_view, 9> kMeshExtensions = {
    ".stl", ".obj", ".dae", ".ply", ".off", ".3ds", ".fbx", ".gltf", ".glb"};

// The path with every symlink resolved, or nothing (it does not exist).
std::optional<std::string> real_path(const std::string& path) {
  char* resolved = realpath(path.c_str(), nullptr);  // not on civetweb's small stack
  if (!resolved) return std::nullopt;
  std::string text(resolved);
  std::free(resolved);
  return text;
}

// Whether `path` (resolved) lies inside one of `folders` (resolved here).
bool inside_a_folder(const std::string& path, const std::vector<std::string>& folders) {
  for (const std::string& listed : folders) {
    const std::optional<std::string> folder = real_path(listed);
    if (!folder) continue;
    const std::string prefix = *folder == "/" ? "/" : *folder + "/";
    if (path.starts_with(prefix)) return true;
  }
  return false;
}

}  // namespace

bool is_mesh_extension(std::string_view path) {
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (std::string_view known : kMeshExtensions)
    if (extension == known) return true;
  return false;
}

MeshFile::MeshFile(const ViewScene& scene, std::string_view index_text) {
  open(scene, index_text);
}

void MeshFile::open(const ViewScene& scene, std::string_view index_text) {
  std::size_t index = 0;
  const char* end = index_text.data() + index_text.size();
  const auto [at, error] = std::from_chars(index_text.data(), end, index);
  if (index_text.empty() || error != std::errc() || at != end || index >= scene.meshes.size() ||
      scene.meshes[index].empty())
    return refuse(404, "not a mesh the scene lists: /mesh/N serves the N-th mesh of /scene.json");
  // The reply names the mesh's number, never its path: the page learns no path of this machine.
  const std::string body = "mesh " + std::to_string(index) + " ";
  if (!is_mesh_extension(scene.meshes[index]))
    return refuse(403, body +
                           "is not of a mesh format (.stl, .obj, .dae, .ply, .off, .3ds, .fbx, "
                           ".gltf, .glb): not served");
  const std::optional<std::string> path = real_path(scene.meshes[index]);
  if (!path) return refuse(404, body + "does not exist");
  // The resolved name is checked as well: a symlink must not lead out of a model folder
  // or to another kind of file.
  if (!is_mesh_extension(*path))
    return refuse(403, body + "leads to a file not of a mesh format: not served");
  if (!inside_a_folder(*path, scene.model_folders))
    return refuse(403, body + "is outside the model folders the physics loaded: not served");
  // No symlink at open (one swapped in since realpath), no FIFO to hang on, and the
  // file opened is the one checked (a folder on its path swapped for a symlink).
  fd_ = ::open(path->c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  struct stat status {};
  if (fd_ < 0 || fstat(fd_, &status) != 0 || !S_ISREG(status.st_mode))
    return refuse(403, body + "is not a regular file: not served");
  const std::optional<std::string> opened = real_path("/proc/self/fd/" + std::to_string(fd_));
  if (opened != path) return refuse(403, body + "changed while it was opened: not served");
  size_ = static_cast<std::size_t>(status.st_size);
}

MeshFile::~MeshFile() {
  if (fd_ >= 0) close(fd_);
}

void MeshFile::refuse(int status, std::string problem) {
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
  status_ = status;
  problem_ = std::move(problem);
}

}  // namespace afhub::viewer
