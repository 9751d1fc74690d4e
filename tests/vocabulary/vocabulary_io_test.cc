#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "ddl/core/error.h"
#include "ddl/vocabulary/vocabulary.h"
#include "ddl/vocabulary/vocabulary_training.h"
#include "synthetic_descriptors.h"

namespace ddl::vocabulary {
namespace {

namespace fs = std::filesystem;

class VocabularyFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("ddl_vocabulary_io_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    std::mt19937_64 rng(8);
    const std::vector<Descriptor> prototypes = test::random_descriptors(300, rng);
    std::vector<cv::Mat> images;
    for (int i = 0; i < 30; ++i) {
      images.push_back(descriptors_to_mat(test::random_image(prototypes, 80, 8, rng)));
    }
    VocabularyConfig config;
    config.branching = 4;
    config.levels = 3;
    vocabulary_ = train_vocabulary(images, config);
    vocabulary_.set_descriptor_tag(0x0123456789ABCDEFull);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  std::string saved_bytes() {
    const std::string p = path("v.dvoc");
    vocabulary_.save(p);
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
  }

  void write_bytes(const std::string& p, const std::string& bytes) {
    std::ofstream out(p, std::ios::binary);
    out << bytes;
  }

  // Loading `bytes` throws an InputError naming the file and containing `what`.
  void expect_load_error(const std::string& bytes, const std::string& what) {
    const std::string p = path("broken.dvoc");
    write_bytes(p, bytes);
    try {
      Vocabulary::load(p);
      FAIL() << "expected an InputError containing '" << what << "'";
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(p), std::string::npos) << message;
      EXPECT_NE(message.find(what), std::string::npos) << message;
    }
  }

  fs::path dir_;
  Vocabulary vocabulary_;
};

TEST_F(VocabularyFile, SaveLoadRoundTripIsExact) {
  const std::string p = path("v.dvoc");
  vocabulary_.save(p);
  const Vocabulary loaded = Vocabulary::load(p);
  EXPECT_TRUE(loaded == vocabulary_);
  EXPECT_EQ(loaded.nodes(), vocabulary_.nodes());
  EXPECT_EQ(loaded.branching(), 4);
  EXPECT_EQ(loaded.levels(), 3);
  EXPECT_EQ(loaded.weighting(), Weighting::kTfIdf);
  EXPECT_EQ(loaded.word_count(), vocabulary_.word_count());
  EXPECT_EQ(loaded.descriptor_tag(), 0x0123456789ABCDEFull);
  EXPECT_EQ(fs::file_size(p), 40 + 40 * vocabulary_.node_count() + 8);
  std::mt19937_64 rng(1);
  const cv::Mat d = descriptors_to_mat(test::random_descriptors(200, rng));
  BowVector b1, b2;
  FeatureVector f1, f2;
  vocabulary_.transform(d, 1, b1, f1);
  loaded.transform(d, 1, b2, f2);
  EXPECT_EQ(b1, b2);
  EXPECT_EQ(f1, f2);
  // Saving the loaded vocabulary gives the same bytes.
  const std::string p2 = path("v2.dvoc");
  loaded.save(p2);
  std::ifstream a(p, std::ios::binary), b(p2, std::ios::binary);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}),
            std::string(std::istreambuf_iterator<char>(b), {}));
  EXPECT_FALSE(fs::exists(p + ".tmp"));
}

TEST_F(VocabularyFile, MissingFileIsNamed) {
  try {
    Vocabulary::load(path("absent.dvoc"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path("absent.dvoc")), std::string::npos);
  }
}

TEST_F(VocabularyFile, WrongMagicIsRejected) {
  std::string bytes = saved_bytes();
  bytes[0] = 'X';
  expect_load_error(bytes, "wrong magic");
  expect_load_error("# a text file, not a vocabulary\n", "wrong magic");
}

TEST_F(VocabularyFile, WrongVersionIsRejected) {
  std::string bytes = saved_bytes();
  bytes[8] = 7;
  expect_load_error(bytes, "version 7");
}

TEST_F(VocabularyFile, TruncatedFileIsRejected) {
  const std::string bytes = saved_bytes();
  // An empty file (a failed copy) or a few bytes of a real one are named as what they are, not
  // as a wrong magic (review, stop 26).
  expect_load_error("", "empty file");
  expect_load_error(bytes.substr(0, 5), "truncated: 5 bytes");
  expect_load_error(bytes.substr(0, 20), "truncated");
  expect_load_error(bytes.substr(0, bytes.size() - 1), "truncated");
  expect_load_error(bytes.substr(0, 40 + 40 * 5), "truncated");
  expect_load_error(bytes + "extra", "does not match");
}

TEST_F(VocabularyFile, CorruptedByteFailsTheChecksum) {
  std::string bytes = saved_bytes();
  bytes[40 + 40 * 7 + 10] ^= 0x10;  // one bit of node 7's descriptor
  expect_load_error(bytes, "checksum");
}

TEST_F(VocabularyFile, SaveToUnwritablePathNamesIt) {
  // A regular file stands where the folder would be created.
  { std::ofstream(path("no_such_dir")) << "a file"; }
  const std::string p = path("no_such_dir/v.dvoc");
  try {
    vocabulary_.save(p);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_dir"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Vocabulary().save(path("empty.dvoc")), Error);
}

}  // namespace
}  // namespace ddl::vocabulary
