#include "ddl/core/filesystem.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <iterator>
#include <stdexcept>
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

// A file in the way (as the folder itself or as one of its parents) is an OutputError (exit code
// 1, as every output that cannot be written) that names the folder and what it was for.
TEST_F(CreateFolderTest, AFileInTheWayIsAnOutputErrorNamingTheFolderAndItsUse) {
  const fs::path file = root_ / "taken";
  std::ofstream(file) << "x";
  for (const fs::path& folder : {file, file / "below"}) {
    try {
      create_folder(folder, "the masks");
      ADD_FAILURE() << "no error for " << folder;
    } catch (const OutputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(folder.string()), std::string::npos) << message;
      EXPECT_NE(message.find("cannot create the folder for the masks"), std::string::npos)
          << message;
    }
  }
  EXPECT_THROW(create_parent_folder(file / "out.txt", "the trajectory"), OutputError);
  EXPECT_TRUE(fs::is_regular_file(file));
}

std::string read_all(const fs::path& file) {
  std::ifstream in(file);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A file is replaced whole or not at all: a failed or throwing writer leaves the previous file
// and no temporary file; a successful one replaces it.
TEST_F(CreateFolderTest, AnAtomicWriteReplacesTheFileWholeOrNotAtAll) {
  const fs::path file = root_ / "out" / "summary.json";
  const auto writes = [](const std::string& text) {
    return [text](std::ostream& out) {
      out << text;
      return true;
    };
  };
  write_file_atomically(file, "the test's summary", writes("first"));
  EXPECT_EQ(read_all(file), "first");
  write_file_atomically(file, "the test's summary", writes("second"));
  EXPECT_EQ(read_all(file), "second");

  try {
    write_file_atomically(file, "the test's summary", [](std::ostream& out) {
      out << "half";
      return false;
    });
    ADD_FAILURE() << "no error for a failed write";
  } catch (const OutputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(file.string()), std::string::npos) << message;
    EXPECT_NE(message.find("cannot write the test's summary"), std::string::npos) << message;
  }
  EXPECT_THROW(write_file_atomically(file, "the test's summary",
                                     [](std::ostream& out) -> bool {
                                       out << "half";
                                       throw std::runtime_error("the writer failed");
                                     }),
               std::runtime_error);
  EXPECT_EQ(read_all(file), "second");
  EXPECT_FALSE(fs::exists(root_ / "out" / "summary.json.partial"));

  // A folder where the file should go: the rename fails, nothing is left behind.
  fs::create_directories(root_ / "out" / "taken");
  EXPECT_THROW(write_file_atomically(root_ / "out" / "taken", "the test's file", writes("x")),
               OutputError);
  EXPECT_TRUE(fs::is_directory(root_ / "out" / "taken"));
  EXPECT_FALSE(fs::exists(root_ / "out" / "taken.partial"));

  // A symbolic link stays a link: its target is written.
  fs::create_symlink(file, root_ / "out" / "link.json");
  write_file_atomically(root_ / "out" / "link.json", "the test's summary", writes("third"));
  EXPECT_TRUE(fs::is_symlink(root_ / "out" / "link.json"));
  EXPECT_EQ(read_all(file), "third");
}

// A device is written into, never replaced (as root, a rename would put a regular file in
// /dev/full's place): the full disk it simulates is an OutputError.
TEST_F(CreateFolderTest, ADeviceIsWrittenIntoNotReplaced) {
  if (!fs::is_character_file("/dev/full")) GTEST_SKIP() << "no /dev/full";
  EXPECT_THROW(write_file_atomically("/dev/full", "the test's file",
                                     [](std::ostream& out) {
                                       out << std::string(1 << 16, 'x');
                                       return true;
                                     }),
               OutputError);
  EXPECT_TRUE(fs::is_character_file("/dev/full"));
  EXPECT_FALSE(fs::exists("/dev/full.partial"));
}

}  // namespace
}  // namespace ddl
