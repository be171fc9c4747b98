// A fuzz test of mesh reading (issue 27): small STL (ASCII and binary), OBJ, PLY
// (ASCII and binary) and OFF meshes, mutated deterministically (bytes flipped, cut
// short, numbers replaced by extremes, lines deleted or duplicated, random bytes
// inserted), are read in batches as the physics reads a model's meshes. This process
// must never die (a crash of assimp ends only its reader process), every file must
// get a mesh whose indices name its vertices or an error naming the file, and a
// reader that dies on one file must not cost the others of its batch their results.
// AFHUB_FUZZ_CASES sets the number of cases (default 300), AFHUB_FUZZ_SEED the seed.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>

#include "afhub/physics/mesh.hpp"
#include "afhub/shm_layout/error.hpp"
#include "mesh_reader.hpp"
#include "model_files.hpp"

namespace afhub::physics {
namespace {

std::uint64_t from_environment(const char* name, std::uint64_t fallback) {
  const char* text = std::getenv(name);
  return text && *text ? std::strtoull(text, nullptr, 10) : fallback;
}

struct Seed {
  std::string extension;
  std::string bytes;
};

std::string binary_stl() {
  std::string bytes(80, ' ');
  const std::uint32_t count = 2;
  bytes.append(reinterpret_cast<const char*>(&count), 4);
  const float triangles[2][12] = {{0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0},
                                  {0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 0}};
  for (const auto& t : triangles) {
    bytes.append(reinterpret_cast<const char*>(t), sizeof t);
    bytes.append(2, '\0');
  }
  return bytes;
}

std::string binary_ply() {
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n"
      "property float y\nproperty float z\nelement face 2\n"
      "property list uchar int vertex_indices\nend_header\n";
  const float vertices[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  bytes.append(reinterpret_cast<const char*>(vertices), sizeof vertices);
  const std::int32_t faces[2][3] = {{0, 1, 2}, {0, 1, 3}};
  for (const auto& f : faces) {
    bytes.push_back(3);
    bytes.append(reinterpret_cast<const char*>(f), sizeof f);
  }
  return bytes;
}

std::vector<Seed> seeds() {
  return {
      {".stl",
       "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
       "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\n"
       "vertex 0 1 0\nendloop\nendfacet\nendsolid s\n"},
      {".stl", binary_stl()},
      {".obj",
       "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nf 1//1 2//1 3//1\nf 1 2 4\n"
       "f 1 3 4 2\n"},
      {".ply",
       "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
       "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
       "end_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n4 0 1 3 2\n"},
      {".ply", binary_ply()},
      {".off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n"},
  };
}

// One mutation of `bytes`, chosen by `random`.
void mutate(std::string& bytes, std::mt19937_64& random) {
  auto pick = [&](std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(random() % n); };
  static const std::vector<std::string> kExtremes = {
      "-1", "0", "4294967295", "2147483648", "99999999999", "1e39", "nan", "-inf", "65536"};
  switch (random() % 6) {
    case 0:  // a byte flipped
      if (!bytes.empty()) bytes[pick(bytes.size())] ^= static_cast<char>(1u << (random() % 8));
      break;
    case 1:  // cut short
      bytes.resize(pick(bytes.size() + 1));
      break;
    case 2: {  // a number replaced by an extreme
      static const std::regex kNumber(R"(-?[0-9]+(\.[0-9]+)?)");
      std::vector<std::pair<std::size_t, std::size_t>> numbers;
      for (std::sregex_iterator it(bytes.begin(), bytes.end(), kNumber), end; it != end; ++it)
        numbers.emplace_back(it->position(), it->length());
      if (numbers.empty()) break;
      const auto [at, length] = numbers[pick(numbers.size())];
      bytes.replace(at, length, kExtremes[pick(kExtremes.size())]);
      break;
    }
    case 3: {  // a line deleted or duplicated
      std::vector<std::size_t> starts = {0};
      for (std::size_t i = 0; i < bytes.size(); ++i)
        if (bytes[i] == '\n') starts.push_back(i + 1);
      const std::size_t line = pick(starts.size());
      const std::size_t begin = starts[line];
      const std::size_t end = line + 1 < starts.size() ? starts[line + 1] : bytes.size();
      if (random() % 2)
        bytes.erase(begin, end - begin);
      else
        bytes.insert(begin, bytes.substr(begin, end - begin));
      break;
    }
    default: {  // random bytes inserted
      std::string noise(1 + pick(8), '\0');
      for (char& c : noise) c = static_cast<char>(random());
      bytes.insert(pick(bytes.size() + 1), noise);
      break;
    }
  }
}

TEST(MeshFuzz, NoMeshFileCrashesThisProcessAndEveryFailureNamesItsFile) {
  const std::uint64_t cases = from_environment("AFHUB_FUZZ_CASES", 300);
  const std::uint64_t seed = from_environment("AFHUB_FUZZ_SEED", 27);
  std::mt19937_64 random(seed);
  const std::vector<Seed> kinds = seeds();
  const afhub::testing::ModelFolder folder;
  MeshReaderOptions options;
  options.time_per_mesh = std::chrono::seconds(3);  // a hang costs the test 3 s, not 40
  constexpr std::size_t kBatch = 25;
  std::size_t read = 0, refused = 0, crashed = 0, stopped = 0;
  for (std::uint64_t first = 0; first < cases; first += kBatch) {
    std::vector<std::string> paths;
    for (std::uint64_t c = first; c < std::min<std::uint64_t>(cases, first + kBatch); ++c) {
      const Seed& kind = kinds[c % kinds.size()];
      std::string bytes = kind.bytes;
      for (std::uint64_t m = 0, n = 1 + random() % 3; m < n; ++m) mutate(bytes, random);
      paths.push_back((folder.dir() / ("case" + std::to_string(c) + kind.extension)).string());
      std::ofstream(paths.back(), std::ios::binary) << bytes;
    }
    const std::vector<MeshReadResult> results = read_mesh_files(paths, options);
    ASSERT_EQ(results.size(), paths.size());
    for (std::size_t i = 0; i < paths.size(); ++i) {
      const MeshReadResult& result = results[i];
      SCOPED_TRACE(paths[i] + " (AFHUB_FUZZ_SEED=" + std::to_string(seed) + ")");
      if (!result.error.empty()) {
        ++refused;
        crashed += result.error.find("crashed on it") != std::string::npos;
        stopped += result.error.find("took more than") != std::string::npos;
        EXPECT_EQ(result.error.rfind(paths[i] + ": error: ", 0), 0u) << result.error;
        continue;
      }
      ++read;
      const std::size_t vertices = result.mesh.xyz.size() / 3;
      EXPECT_EQ(result.mesh.xyz.size() % 3, 0u);
      EXPECT_EQ(result.mesh.triangles.size() % 3, 0u);
      for (std::uint32_t index : result.mesh.triangles) ASSERT_LT(index, vertices);
      // What the physics makes of it: a mesh, or an error naming the file.
      try {
        load_mesh(paths[i], 1.0);
      } catch (const Error& error) {
        EXPECT_EQ(std::string(error.what()).rfind(paths[i] + ": error: ", 0), 0u) << error.what();
      }
    }
  }
  // Both outcomes happen: the mutations neither always break nor never break a mesh.
  EXPECT_GT(read, 0u);
  EXPECT_GT(refused, 0u);
  std::printf("%zu meshes read, %zu refused (the reader crashed on %zu, was stopped on %zu)\n",
              read, refused, crashed, stopped);
}

}  // namespace
}  // namespace afhub::physics
