#include "ddl/core/filesystem.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "ddl/core/error.h"

namespace ddl {
namespace {

namespace fs = std::filesystem;

class CreateFolderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("ddl_create_folder_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
};

TEST_F(CreateFolderTest, CreatesMissingParentsAndAcceptsAnExistingFolder) {
  const fs::path folder = root_ / "a" / "b" / "c";
  create_folder(folder, "the test");
  EXPECT_TRUE(fs::is_directory(folder));
  EXPECT_NO_THROW(create_folder(folder, "the test"));
  create_parent_folder(root_ / "d" / "e" / "file.txt", "the test's file");
  EXPECT_TRUE(fs::is_directory(root_ / "d" / "e"));
  EXPECT_FALSE(fs::exists(root_ / "d" / "e" / "file.txt"));
  EXPECT_NO_THROW(create_parent_folder("file_in_the_working_folder.txt", "nothing"));
}

// A file in the way (as the folder itself or as one of its parents) is an InputError that names
// the folder and what it was for.
TEST_F(CreateFolderTest, AFileInTheWayIsAnInputErrorNamingTheFolderAndItsUse) {
  const fs::path file = root_ / "taken";
  std::ofstream(file) << "x";
  for (const fs::path& folder : {file, file / "below"}) {
    try {
      create_folder(folder, "the masks");
      ADD_FAILURE() << "no error for " << folder;
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(folder.string()), std::string::npos) << message;
      EXPECT_NE(message.find("cannot create the folder for the masks"), std::string::npos)
          << message;
    }
  }
  EXPECT_THROW(create_parent_folder(file / "out.txt", "the trajectory"), InputError);
  EXPECT_TRUE(fs::is_regular_file(file));
}

}  // namespace
}  // namespace ddl
