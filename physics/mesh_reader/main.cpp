// afhub-mesh-reader FILE...: reads each mesh file with assimp and writes its triangles
// on standard output (physics/src/mesh_wire.hpp). The physics starts it rather than
// parse meshes itself: assimp was not written for hostile input, and a file that
// crashes it, hangs it or makes it grow takes down this short-lived process, within
// limits it sets on itself before it opens any file, never the physics or `afhub check`.
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fcntl.h>
#include <malloc.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <assimp/DefaultIOStream.h>
#include <assimp/DefaultIOSystem.h>
#include <algorithm>
#include <assimp/Importer.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include "afhub/physics/mesh.hpp"
#include "mesh_wire.hpp"
#include "path_kind.hpp"

namespace {

using namespace afhub::physics;

void limit(int resource, rlim_t value) {
  const rlimit bound{value, value};
  setrlimit(resource, &bound);
}

// CPU time for the next file: 20 s more than used so far (SIGXCPU ends the process).
void limit_cpu_for_next_file() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  rlimit cpu{};
  getrlimit(RLIMIT_CPU, &cpu);
  const auto used = static_cast<rlim_t>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec + 1);
  cpu.rlim_cur = std::min<rlim_t>(used + mesh_wire::kCpuSecondsPerMesh, cpu.rlim_max);
  setrlimit(RLIMIT_CPU, &cpu);
}

// Assimp opens the mesh and every file it names (an OBJ's mtllib, a texture) through
// this: regular files only, opened without blocking (a FIFO would wait for a writer
// forever), read-only. A file that exists but is not regular is remembered: the mesh
// is refused, naming it.
class RegularFilesOnly : public Assimp::DefaultIOSystem {
 public:
  bool Exists(const char* path) const override { return regular(path); }
  Assimp::IOStream* Open(const char* path, const char* mode) override {
    if (std::strpbrk(mode, "wa+")) return nullptr;
    const int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
    if (fd < 0) {
      regular(path);
      return nullptr;
    }
    struct stat status {};
    FILE* file = nullptr;
    if (fstat(fd, &status) == 0 && S_ISREG(status.st_mode))
      file = fdopen(fd, "rb");
    else
      refused = "it names '" + std::string(path) + "', which " + not_a_regular_file(path);
    if (!file) {
      close(fd);
      return nullptr;
    }
    return new Stream(file, path);
  }
  // Why a file it named was refused ("" when none was).
  mutable std::string refused;

 private:
  bool regular(const char* path) const {
    const std::string what = not_a_regular_file(path);
    if (what.empty()) return true;
    if (what != "does not exist" && what.rfind("is a broken symlink", 0) != 0)
      refused = "it names '" + std::string(path) + "', which " + what;
    return false;
  }
  struct Stream : Assimp::DefaultIOStream {
    Stream(FILE* file, const std::string& name) : DefaultIOStream(file, name) {}
  };
};

// PLY and OFF headers declare how many elements follow, and assimp allocates and
// loops by them: a count that cannot fit in the file (each element takes at least a
// byte) is refused before assimp sees it. Returns why, or "".
std::string check_declared_counts(const char* path) {
  const int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  struct stat status {};
  if (fd < 0 || fstat(fd, &status) != 0 || !S_ISREG(status.st_mode)) {
    if (fd >= 0) close(fd);
    return "";  // RegularFilesOnly refuses it, saying why
  }
  std::string head(65536, '\0');
  const ssize_t got = ::read(fd, head.data(), head.size());
  close(fd);
  head.resize(got > 0 ? static_cast<std::size_t>(got) : 0);
  const auto size = static_cast<unsigned long long>(status.st_size);
  std::istringstream lines(head);
  std::string line;
  std::getline(lines, line);
  const bool ply = line.rfind("ply", 0) == 0;
  const bool off = !ply && line.find("OFF") != std::string::npos;
  if (!ply && !off) return "";
  unsigned long long declared = 0;
  auto add = [&declared](const std::string& count) {
    unsigned long long n = ~0ULL;  // not a count assimp could read either: refused too
    try {
      n = std::stoull(count);
    } catch (const std::exception&) {
    }
    declared = n > ~0ULL - declared ? ~0ULL : declared + n;
  };
  if (off) {
    // The counts: the first line after the keyword that is not a comment (and may
    // follow it on its line).
    std::string counts = line.substr(line.find("OFF") + 3);
    while (counts.find_first_not_of(" \t\r") == std::string::npos || counts[0] == '#')
      if (!std::getline(lines, counts)) return "";
    std::istringstream words(counts);
    std::string vertices, faces;
    if (words >> vertices >> faces) {
      add(vertices);
      add(faces);
    }
  } else {
    std::string count;
    bool ended = false;
    for (bool in_element = false; !ended && std::getline(lines, line);) {
      ended = line.rfind("end_header", 0) == 0;
      std::istringstream words(line);
      std::string keyword, name;
      words >> keyword;
      if (keyword == "element") {
        in_element = static_cast<bool>(words >> name >> count);
      } else if (keyword == "property" && in_element) {
        add(count);  // an element with properties takes bytes
        in_element = false;
      }
    }
    // assimp loops forever on some headers cut short.
    if (!ended)
      return "its header has no end_header line in its first " + std::to_string(head.size()) +
             " bytes; the file is cut short or is not a PLY";
  }
  if (declared <= size) return "";
  return "its header declares " + (declared == ~0ULL ? "an unreadable" : std::to_string(declared)) +
         " elements, more than its " + std::to_string(size) +
         " bytes can hold; the file is cut short or its header is wrong";
}

struct Mesh {
  std::vector<float> xyz;
  std::vector<std::uint32_t> triangles;
};

// Reads every part of `path` into `mesh`, node transforms applied; returns why it
// cannot be used, or "".
std::string read(Assimp::Importer& importer, RegularFilesOnly& files, const char* path,
                 Mesh& mesh) {
  if (std::string why = check_declared_counts(path); !why.empty()) return why;
  files.refused.clear();
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                  aiProcess_PreTransformVertices);
  if (!files.refused.empty())
    return files.refused + "; a mesh and the files it names must be regular files";
  if (!scene || !scene->mRootNode)
    return std::string("cannot read this mesh: ") + importer.GetErrorString();
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* part = scene->mMeshes[m];
    const std::size_t base = mesh.xyz.size() / 3;
    if (base + part->mNumVertices > kMaxMeshVertices ||
        mesh.triangles.size() / 3 + part->mNumFaces > kMaxMeshTriangles)
      return "the mesh has more than " + std::to_string(kMaxMeshTriangles) + " triangles or " +
             std::to_string(kMaxMeshVertices) +
             " vertices; simplify it (a collision mesh needs far fewer)";
    for (unsigned v = 0; v < part->mNumVertices; ++v) {
      const aiVector3D& p = part->mVertices[v];
      mesh.xyz.insert(mesh.xyz.end(), {p.x, p.y, p.z});
    }
    for (unsigned f = 0; f < part->mNumFaces; ++f) {
      const aiFace& face = part->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines have no volume
      for (unsigned k = 0; k < 3; ++k)
        if (face.mIndices[k] >= part->mNumVertices)
          return "face " + std::to_string(f) + " names a vertex beyond the " +
                 std::to_string(part->mNumVertices) + " of its part; repair the mesh";
      for (unsigned k = 0; k < 3; ++k)
        mesh.triangles.push_back(static_cast<std::uint32_t>(base + face.mIndices[k]));
    }
  }
  return "";
}

void write_all(const void* data, std::size_t bytes) {
  const char* at = static_cast<const char*>(data);
  while (bytes > 0) {
    const ssize_t done = write(STDOUT_FILENO, at, bytes);
    if (done < 0 && errno == EINTR) continue;
    if (done <= 0) _exit(1);  // the physics stopped listening
    at += done;
    bytes -= static_cast<std::size_t>(done);
  }
}

void write_refusal(std::uint32_t index, std::string why) {
  why.resize(std::min(why.size(), mesh_wire::kMaxMessageBytes));
  mesh_wire::Header header;
  header.index = index;
  header.status = mesh_wire::kRefused;
  header.message_bytes = static_cast<std::uint32_t>(why.size());
  write_all(&header, sizeof header);
  write_all(why.data(), why.size());
}

void write_mesh(std::uint32_t index, const Mesh& mesh) {
  mesh_wire::Header header;
  header.index = index;
  header.vertex_count = mesh.xyz.size() / 3;
  header.triangle_count = mesh.triangles.size() / 3;
  write_all(&header, sizeof header);
  write_all(mesh.xyz.data(), mesh.xyz.size() * sizeof(float));
  write_all(mesh.triangles.data(), mesh.triangles.size() * sizeof(std::uint32_t));
}

}  // namespace

int main(int argc, char** argv) {
#if !defined(AFHUB_SANITIZED)
  // (AddressSanitizer reserves terabytes of address space for its shadow memory: the
  // sanitizer build goes without this one limit.)
  limit(RLIMIT_AS, mesh_wire::kAddressSpaceBytes);
#endif
  limit(RLIMIT_FSIZE, 0);
  limit(RLIMIT_CORE, 0);
  limit(RLIMIT_NOFILE, 64);
  // Memory freed after one file is kept for the next: not returned to the kernel and
  // faulted in again (a large part of the cost of reading small meshes).
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  // One importer for every file: making one sets up all of assimp's format readers.
  Assimp::Importer importer;
  auto* files = new RegularFilesOnly;
  importer.SetIOHandler(files);  // the importer deletes it
  for (int i = 1; i < argc; ++i) {
    limit_cpu_for_next_file();
    const auto index = static_cast<std::uint32_t>(i - 1);
    std::string why;
    Mesh mesh;
    try {
      why = read(importer, *files, argv[i], mesh);
    } catch (const std::bad_alloc&) {
      why = "reading it needs more than " + std::to_string(mesh_wire::kAddressSpaceBytes >> 30) +
            " GB of memory; is it a mesh, and is its header right?";
    } catch (const std::exception& error) {
      why = std::string("cannot read this mesh: ") + error.what();
    }
    if (why.empty())
      write_mesh(index, mesh);
    else
      write_refusal(index, why);
  }
  return 0;
}
