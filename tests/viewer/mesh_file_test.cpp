// What /mesh/N opens (viewer/src/mesh_file.hpp): only a regular file of a mesh format
// within the scene's model folders, whatever the scene names.
#include "mesh_file.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace afhub::viewer {
namespace {

namespace fs = std::filesystem;

class MeshFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/afhub_mesh_file_test_XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
    fs::create_directories(dir_ + "/model/meshes");
    fs::create_directories(dir_ + "/home/.ssh");
    std::ofstream(dir_ + "/model/meshes/arm.STL") << "solid arm\nendsolid arm\n";
    std::ofstream(dir_ + "/home/.ssh/id_ed25519") << "PRIVATE KEY";
    std::ofstream(dir_ + "/home/photo.stl") << "outside the model";
    scene_.model_folders = {dir_ + "/model"};
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Opens what scene body 0 names; its status (200 when it would be served).
  int status_of(const std::string& path) {
    scene_.meshes = {path};
    const MeshFile mesh(scene_, "0");
    problem_ = mesh.problem();
    EXPECT_EQ(problem_.find(dir_), std::string::npos) << "a reply names no path: " << problem_;
    return mesh.problem().empty() ? 200 : mesh.status();
  }

  std::string dir_, problem_;
  ViewScene scene_;
};

TEST_F(MeshFileTest, AMeshInAModelFolderIsOpened) {
  scene_.meshes = {dir_ + "/model/meshes/arm.STL"};
  const MeshFile mesh(scene_, "0");
  EXPECT_EQ(mesh.problem(), "");
  EXPECT_GE(mesh.fd(), 0);
  EXPECT_EQ(mesh.size(), fs::file_size(dir_ + "/model/meshes/arm.STL"));
}

TEST_F(MeshFileTest, AFileNotOfAMeshFormatIsRefused) {
  EXPECT_EQ(status_of(dir_ + "/home/.ssh/id_ed25519"), 403);
  EXPECT_NE(problem_.find("mesh format"), std::string::npos) << problem_;
  // Even inside a model folder.
  fs::copy_file(dir_ + "/home/.ssh/id_ed25519", dir_ + "/model/meshes/key.pem");
  EXPECT_EQ(status_of(dir_ + "/model/meshes/key.pem"), 403);
}

TEST_F(MeshFileTest, AMeshOutsideTheModelFoldersIsRefused) {
  EXPECT_EQ(status_of(dir_ + "/home/photo.stl"), 403);
  EXPECT_NE(problem_.find("outside the model folders"), std::string::npos) << problem_;
  EXPECT_EQ(status_of(dir_ + "/model/meshes/../../home/photo.stl"), 403);
  // A folder whose name begins like a model folder's is not inside it.
  fs::create_directories(dir_ + "/model2");
  std::ofstream(dir_ + "/model2/arm.stl") << "solid x\nendsolid x\n";
  EXPECT_EQ(status_of(dir_ + "/model2/arm.stl"), 403);
  scene_.model_folders.clear();
  EXPECT_EQ(status_of(dir_ + "/model/meshes/arm.STL"), 403) << "no model folder, no mesh";
}

TEST_F(MeshFileTest, ASymlinkOutOfTheFolderOrToAnotherKindOfFileIsRefused) {
  fs::create_symlink(dir_ + "/home/.ssh/id_ed25519", dir_ + "/model/meshes/key.stl");
  EXPECT_EQ(status_of(dir_ + "/model/meshes/key.stl"), 403) << problem_;
  fs::create_symlink(dir_ + "/home/photo.stl", dir_ + "/model/meshes/photo.stl");
  EXPECT_EQ(status_of(dir_ + "/model/meshes/photo.stl"), 403) << problem_;
  fs::create_symlink(dir_ + "/home", dir_ + "/model/linked");
  EXPECT_EQ(status_of(dir_ + "/model/linked/photo.stl"), 403) << problem_;
}

TEST_F(MeshFileTest, AFifoDirectoryOrDeviceIsRefusedWithoutWaiting) {
  ASSERT_EQ(mkfifo((dir_ + "/model/meshes/fifo.stl").c_str(), 0600), 0);
  EXPECT_EQ(status_of(dir_ + "/model/meshes/fifo.stl"), 403) << "opened without hanging";
  EXPECT_NE(problem_.find("not a regular file"), std::string::npos) << problem_;
  fs::create_directories(dir_ + "/model/meshes/dir.stl");
  EXPECT_EQ(status_of(dir_ + "/model/meshes/dir.stl"), 403);
  scene_.model_folders = {"/"};
  EXPECT_EQ(status_of("/dev/zero.stl"), 404);
  fs::create_symlink("/dev/zero", dir_ + "/model/meshes/zero.stl");
  EXPECT_EQ(status_of(dir_ + "/model/meshes/zero.stl"), 403);
}

TEST_F(MeshFileTest, OnlyAListedBodysMeshIsNamed) {
  scene_.meshes = {dir_ + "/model/meshes/arm.STL", ""};
  for (const char* index : {"1", "2", "-1", "", "0/../1", "00x", "99999999999999999999"}) {
    const MeshFile mesh(scene_, index);
    EXPECT_EQ(mesh.status(), 404) << index;
  }
}

}  // namespace
}  // namespace afhub::viewer
