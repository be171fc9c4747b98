// Meshes written to break assimp (issue 27): each is a located error naming the mesh
// and exit 1 from `afhub check` and `afhub run`, never a crash (assimp's abort, a
// SIGSEGV), a hang (an OBJ whose mtllib is a FIFO, a PLY that declares 100 million
// vertices) or unbounded growth. Needs no hub: `check` never connects, and `run
// --offline` refuses the model before it would step.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>

#include "afhub_process.hpp"
#include "model_files.hpp"
#include "strict_json.hpp"

namespace afhub::test {
namespace {

namespace fs = std::filesystem;

struct Case {
  std::string name;      // what it is
  std::string mesh;      // the body's `mesh`
  std::string where;     // the start of the error: where the model names the mesh
  std::string expected;  // a part of the error
};

class MeshFaults : public ::testing::Test {
 protected:
  MeshFaults() {
    // Header: 2 faces; one given. assimp's triangulation asserts (abort).
    folder_.write("faces.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n");
    // A face naming vertex 900000000 of 3: assimp reads past its array (SIGSEGV).
    folder_.write("indices.ply", ply_header("3") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 900000000\n");
    // The material library is a FIFO: opening it waits for a writer forever.
    folder_.write("fifo.obj", "mtllib fifo.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n");
    mkfifo((folder_.dir() / "fifo.mtl").c_str(), 0644);
    // 100 million vertices declared, three given: assimp loops and grows.
    folder_.write("count.ply", ply_header("100000000") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    fs::create_directory(folder_.dir() / "directory.stl");
    fs::create_symlink("loop.stl", folder_.dir() / "loop.stl");
  }
  static std::string ply_header(const std::string& vertices) {
    return "ply\nformat ascii 1.0\nelement vertex " + vertices +
           "\nproperty float x\nproperty float y\nproperty float z\nelement face 1\n"
           "property list uchar int vertex_indices\nend_header\n";
  }
  std::string model_with_mesh(const std::string& mesh) {
    return folder_.write("model.yaml",
                         "bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n  mesh: " + mesh + "\n");
  }
  afhub::testing::ModelFolder folder_;
};

TEST_F(MeshFaults, EachIsALocatedErrorAndExitOneNeverACrashOrAHang) {
  // Read, and refused: where the body names it. Not a file: where its name is.
  const std::string read = "model.yaml:3:3: error: body 'BODY a': its mesh cannot be used: ";
  const std::string named = "model.yaml:5:9: error: mesh '";
  const std::vector<Case> cases = {
      {"face counts that disagree", "faces.off", read, "crashed on it: ABRT"},
      {"face indices past the vertices", "indices.ply", read, "crashed on it: SEGV"},
      {"an mtllib that is a FIFO", "fifo.obj", read, "fifo.mtl', which is a FIFO"},
      {"a huge declared count", "count.ply", read, "its header declares 100000001 elements"},
      {"a directory", "directory.stl", named, "is a directory"},
      {"a symlink loop", "loop.stl", named, "is a symlink loop"},
  };
  for (const Case& c : cases) {
    const std::string model = model_with_mesh(c.mesh);
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"check", model}, {"run", model, "--offline", "--steps", "1"}}) {
      SCOPED_TRACE(c.name + ", afhub " + args[0]);
      // The reader's limits: 20 s of CPU time, 40 s without progress.
      const RunResult result = run_afhub(args, std::chrono::seconds(90));
      EXPECT_EQ(result.exit_code, 1) << result.err;
      EXPECT_TRUE(contains(result.err, c.expected)) << result.err;
      EXPECT_TRUE(contains(result.err, c.where)) << result.err;
      EXPECT_TRUE(contains(result.err, c.mesh)) << result.err;
    }
  }
}

// `afhub run --mesh-fallback box`: the body whose mesh crashes the reader collides as
// the box of its mass and inertia (0.2 x 0.4 x 0.6 m for these), said once; falling
// on a floor whose top is z = 0, its centre comes to rest at half its height. With no
// shape it would fall through, and as a 10 cm cube it would rest at 0.05 m.
TEST_F(MeshFaults, ABodyWhoseMeshCannotBeUsedFallsBackToItsBoxWhenAsked) {
  const std::string model = folder_.write(
      "model.yaml",
      "bodies: [BODY floor, BODY a]\n"
      "BODY floor:\n  name: floor\n  mass: 0\n  shape: BOX\n"
      "  geometry: {x: 4, y: 4, z: 0.2}\n"
      "  location: {position: {x: 0, y: 0, z: -0.1}, orientation: {r: 0, p: 0, y: 0}}\n"
      "BODY a:\n  name: a\n  mass: 12\n  inertia: {ix: 0.52, iy: 0.40, iz: 0.20}\n"
      "  location: {position: {x: 0, y: 0, z: 0.5}, orientation: {r: 0, p: 0, y: 0}}\n"
      "  mesh: faces.off\n");
  const std::string report = (folder_.dir() / "report.json").string();
  const RunResult run = run_afhub({"run", model, "--offline", "--fast", "--steps", "2000",
                                   "--report", report, "--mesh-fallback", "box"},
                                  std::chrono::seconds(90));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string said = "model.yaml:9:3: warning: body 'BODY a': its mesh cannot be used (";
  EXPECT_TRUE(contains(run.err, said)) << run.err;
  EXPECT_EQ(run.err.find(said), run.err.rfind(said)) << "said more than once: " << run.err;
  for (const char* part : {"faces.off", "crashed on it: ABRT",
                           "it collides as a box 0.2 x 0.4 x 0.6 m", "--mesh-fallback box"})
    EXPECT_TRUE(contains(run.err, part)) << part << " in " << run.err;
  const nlohmann::json json = parse_json(read_file(report));
  EXPECT_EQ(json.at("steps"), 2000);
  EXPECT_EQ(json.at("nan_detected"), false);
  const nlohmann::json& position = json.at("bodies").at("ambf/env/a").at("position");
  EXPECT_NEAR(position.at(2).get<double>(), 0.3, 0.01) << position;
  EXPECT_NEAR(position.at(0).get<double>(), 0.0, 0.01) << position;
  // Refused, as before, without the flag.
  const RunResult refused =
      run_afhub({"run", model, "--offline", "--steps", "1"}, std::chrono::seconds(90));
  EXPECT_EQ(refused.exit_code, 1) << refused.err;
  EXPECT_TRUE(
      contains(refused.err, "model.yaml:9:3: error: body 'BODY a': its mesh cannot be used"))
      << refused.err;
}

// Every mesh that the reader cannot use (a crash, a FIFO it would hang on, a count past
// its limits) falls back the same way; a path that is not a file is still refused.
TEST_F(MeshFaults, EveryUnreadableMeshFallsBackAndABadPathIsStillRefused) {
  for (const std::string mesh : {"faces.off", "indices.ply", "fifo.obj", "count.ply"}) {
    SCOPED_TRACE(mesh);
    const RunResult run = run_afhub(
        {"run", model_with_mesh(mesh), "--offline", "--steps", "1", "--mesh-fallback", "box"},
        std::chrono::seconds(90));
    EXPECT_EQ(run.exit_code, 0) << run.err;
    EXPECT_TRUE(contains(run.err,
                         "model.yaml:3:3: warning: body 'BODY a': its mesh cannot be "
                         "used ("))
        << run.err;
    EXPECT_TRUE(contains(run.err, mesh)) << run.err;
  }
  const RunResult refused = run_afhub({"run", model_with_mesh("directory.stl"), "--offline",
                                       "--steps", "1", "--mesh-fallback", "box"},
                                      std::chrono::seconds(90));
  EXPECT_EQ(refused.exit_code, 1) << refused.err;
  EXPECT_TRUE(contains(refused.err, "is a directory")) << refused.err;
}

}  // namespace
}  // namespace afhub::test
