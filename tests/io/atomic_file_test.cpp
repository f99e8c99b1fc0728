#include "tendril/io/atomic_file.h"

#include "support/gltf_validator.h"
#include "tendril/core/error.h"
#include "tendril/io/image.h"

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

namespace tendril::io {
namespace {

namespace fs = std::filesystem;

std::string readAll(const fs::path& p) {
  std::vector<uint8_t> b = readFileBytes(p);
  return std::string(b.begin(), b.end());
}

size_t filesIn(const fs::path& dir) {
  return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

TEST(IoAtomicFile, WritesAndReplaces) {
  fs::path dir = meshtest::exportTestDir();
  writeFileAtomic(dir / "a.txt", std::string_view("first"));
  EXPECT_EQ(readAll(dir / "a.txt"), "first");
  writeFileAtomic(dir / "a.txt", std::string_view("second, longer"));
  EXPECT_EQ(readAll(dir / "a.txt"), "second, longer");
  // Large writes bypass the buffer.
  std::vector<uint8_t> big(5u << 20);
  for (size_t i = 0; i < big.size(); ++i) big[i] = static_cast<uint8_t>(i * 7);
  AtomicFileWriter w(dir / "big.bin");
  w.write(std::string_view("head"));
  w.write(big);
  w.write(std::string_view("tail"));
  w.commit();
  std::vector<uint8_t> back = readFileBytes(dir / "big.bin");
  ASSERT_EQ(back.size(), big.size() + 8);
  EXPECT_TRUE(std::equal(big.begin(), big.end(), back.begin() + 4));
  EXPECT_EQ(filesIn(dir), 2u);  // no temporaries left behind
}

TEST(IoAtomicFile, MissingDirectoryIsAnErrorNamingThePath) {
  fs::path dir = meshtest::exportTestDir();
  fs::path target = dir / "no-such-dir" / "out.glb";
  try {
    writeFileAtomic(target, std::string_view("x"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.source(), target.string());
    EXPECT_NE(e.message().find("does not exist"), std::string::npos) << e.what();
  }
  EXPECT_THROW(writeFileAtomic(dir, std::string_view("x")), Error);  // a directory
}

TEST(IoAtomicFile, AbandonedWriteLeavesTheOldFile) {
  fs::path dir = meshtest::exportTestDir();
  writeFileAtomic(dir / "keep.txt", std::string_view("precious"));
  {
    AtomicFileWriter w(dir / "keep.txt");
    w.write(std::string_view("half-written"));
    // No commit: e.g. an exception while producing the content.
  }
  EXPECT_EQ(readAll(dir / "keep.txt"), "precious");
  EXPECT_EQ(filesIn(dir), 1u);
}

TEST(IoAtomicFile, FailedWriteLeavesTheOldFile) {
  fs::path dir = meshtest::exportTestDir();
  writeFileAtomic(dir / "keep.txt", std::string_view("precious"));
  // A real write failure, even for root: a file size limit makes write() fail with EFBIG.
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  auto oldHandler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit small = old;
  small.rlim_cur = 1 << 16;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string error;
  try {
    writeFileAtomic(dir / "keep.txt", std::string(1 << 20, 'x'));
  } catch (const Error& e) {
    error = e.what();
  }
  setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, oldHandler);
  EXPECT_NE(error.find((dir / "keep.txt").string()), std::string::npos) << error;
  EXPECT_NE(error.find("cannot write"), std::string::npos) << error;
  EXPECT_EQ(readAll(dir / "keep.txt"), "precious");
  EXPECT_EQ(filesIn(dir), 1u);
}

TEST(IoAtomicFile, ReadOnlyDirectory) {
  fs::path dir = meshtest::exportTestDir() / "ro";
  fs::create_directories(dir);
  writeFileAtomic(dir / "keep.txt", std::string_view("precious"));
  ASSERT_EQ(::chmod(dir.c_str(), 0555), 0);
  bool threw = false;
  try {
    writeFileAtomic(dir / "keep.txt", std::string_view("new"));
  } catch (const Error& e) {
    threw = true;
    EXPECT_EQ(e.source(), (dir / "keep.txt").string());
  }
  ::chmod(dir.c_str(), 0755);
  // Root ignores directory permissions; everyone else must get the Error and the old file.
  if (::geteuid() != 0) {
    EXPECT_TRUE(threw);
    EXPECT_EQ(readAll(dir / "keep.txt"), "precious");
  } else {
    EXPECT_EQ(readAll(dir / "keep.txt"), threw ? "precious" : "new");
  }
}

}  // namespace
}  // namespace tendril::io
