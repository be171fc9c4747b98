// The mesh reader process seen from the physics (physics/src/mesh_reader.hpp): a
// reader that hangs is stopped, one that lies in its records is not believed, one
// that dies on a file costs only that file its mesh (issue 27).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>

#include "afhub/physics/mesh.hpp"
#include "afhub/shm_layout/error.hpp"
#include "mesh_reader.hpp"
#include "model_files.hpp"
#include "text_contains.hpp"

namespace afhub::physics {
namespace {

using afhub::test::contains;

class MeshReader : public ::testing::Test {
 protected:
  // A reader that runs `script` (bash) whatever files it is given.
  MeshReaderOptions fake_reader(const std::string& script) {
    MeshReaderOptions options;
    options.program = folder_.write("reader.sh", "#!/bin/bash\n" + script + "\n");
    chmod(options.program.c_str(), 0755);
    options.time_per_mesh = std::chrono::seconds(1);
    return options;
  }
  afhub::testing::ModelFolder folder_;
};

TEST_F(MeshReader, OneThatHangsIsStoppedAndItsFileNamed) {
  const auto start = std::chrono::steady_clock::now();
  const auto results = read_mesh_files({"/a.stl"}, fake_reader("exec sleep 600"));
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(results[0].error,
            "/a.stl: error: reading it took more than 1 s, and was stopped; "
            "is it a mesh?");
  // Stopped, not waited for: far less than the reader's 600 s.
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(60));
}

TEST_F(MeshReader, ARecordThatNamesNoVertexOrIsOutOfOrderIsNotBelieved) {
  // "MESH", index 0, read, no message, 1 vertex, 1 triangle: (0,0,0), then (0, 0, 7).
  const std::string header =
      R"(printf 'MESH\0\0\0\0\0\0\0\0\0\0\0\0\1\0\0\0\0\0\0\0\1\0\0\0\0\0\0\0')";
  const std::string body = R"(printf '\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\7\0\0\0')";
  auto results = read_mesh_files({"/a.stl"}, fake_reader(header + "\n" + body));
  EXPECT_EQ(results[0].error,
            "/a.stl: error: the mesh reader failed: it wrote a triangle naming no vertex");
  results = read_mesh_files({"/a.stl"}, fake_reader("printf 'HSEM%.0s' {1..8}"));
  EXPECT_EQ(results[0].error,
            "/a.stl: error: the mesh reader failed: it wrote a record out of order");
}

TEST_F(MeshReader, OneThatDiesOnAFileCostsOnlyThatFileItsMesh) {
  const std::string triangle =
      "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
      "vertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
  const std::string good = folder_.write("good.stl", triangle);
  // Header: 2 faces; one given. assimp's triangulation asserts (abort).
  const std::string bad =
      folder_.write("bad.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n");
  const std::string also_good = folder_.write("also_good.stl", triangle);
  const auto results = read_mesh_files({good, bad, also_good});
  ASSERT_EQ(results.size(), 3u);
  EXPECT_EQ(results[0].error, "");
  EXPECT_EQ(results[0].mesh.triangles.size(), 3u);
  EXPECT_TRUE(
      contains(results[1].error, bad + ": error: the mesh reader (assimp) crashed on it: ABRT"))
      << results[1].error;
  EXPECT_EQ(results[2].error, "");
  EXPECT_EQ(results[2].mesh.xyz.size(), 9u);
}

TEST_F(MeshReader, AReaderThatCannotBeStartedIsAnError) {
  MeshReaderOptions options;
  options.program = "/nonexistent/afhub-mesh-reader";
  try {
    read_mesh_files({"/a.stl"}, options);
    ADD_FAILURE() << "no error";
  } catch (const Error& error) {
    EXPECT_TRUE(contains(error.what(), "cannot read meshes: cannot start " + options.program))
        << error.what();
  }
}

}  // namespace
}  // namespace afhub::physics
