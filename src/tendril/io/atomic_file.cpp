#include "tendril/io/atomic_file.h"

#include "tendril/core/error.h"

#include <fmt/format.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include <fcntl.h>
#include <unistd.h>

namespace tendril::io {
namespace {

constexpr size_t kBufferBytes = size_t(1) << 20;
constexpr size_t kDirectBytes = size_t(1) << 16;  // writes this large skip the buffer

std::atomic<uint64_t> gTempCounter{0};

std::string errnoText(int err) { return std::strerror(err); }

}  // namespace

void checkOutputPath(const std::filesystem::path& path) {
  std::filesystem::path dir = path.parent_path();
  std::error_code ec;
  if (path.filename().empty()) throw Error(path.string(), "", "cannot write: not a file name");
  if (!dir.empty() && !std::filesystem::is_directory(dir, ec))
    throw Error(path.string(), "", fmt::format("cannot write: directory {} does not exist", dir.string()));
  if (std::filesystem::is_directory(path, ec)) throw Error(path.string(), "", "cannot write: it is a directory");
}

AtomicFileWriter::AtomicFileWriter(std::filesystem::path path) : path_(std::move(path)) {
  checkOutputPath(path_);
  std::filesystem::path dir = path_.parent_path();
  // A hidden name in the same directory (rename() is atomic only within a file system),
  // unique per process and writer.
  temp_ = dir / fmt::format(".{}.{}-{}.tmp", path_.filename().string(), static_cast<long>(::getpid()),
                            gTempCounter.fetch_add(1));
  fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd_ < 0) throw Error(path_.string(), "", "cannot write: " + errnoText(errno));
  buffer_ = std::make_unique<char[]>(kBufferBytes);
}

AtomicFileWriter::~AtomicFileWriter() {
  if (!committed_) discard();
}

void AtomicFileWriter::discard() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!temp_.empty()) ::unlink(temp_.c_str());
  temp_.clear();
}

void AtomicFileWriter::fail(const std::string& what) {
  discard();
  throw Error(path_.string(), "", what);
}

void AtomicFileWriter::flushBuffer() {
  const char* p = buffer_.get();
  size_t left = buffered_;
  buffered_ = 0;
  while (left > 0) {
    ssize_t n = ::write(fd_, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("cannot write: " + errnoText(errno));
    }
    p += n;
    left -= static_cast<size_t>(n);
  }
}

void AtomicFileWriter::write(const void* data, size_t bytes) {
  if (fd_ < 0 || committed_) throw Error(path_.string(), "", "cannot write: the file is already closed");
  written_ += bytes;
  const char* p = static_cast<const char*>(data);
  if (bytes < kDirectBytes) {
    if (buffered_ + bytes > kBufferBytes) flushBuffer();
    std::memcpy(buffer_.get() + buffered_, p, bytes);
    buffered_ += bytes;
    return;
  }
  // Large blocks go straight to the kernel, without another copy.
  flushBuffer();
  while (bytes > 0) {
    ssize_t n = ::write(fd_, p, bytes);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("cannot write: " + errnoText(errno));
    }
    p += n;
    bytes -= static_cast<size_t>(n);
  }
}

void AtomicFileWriter::writeAt(uint64_t offset, const void* data, size_t bytes) {
  if (fd_ < 0 || committed_) throw Error(path_.string(), "", "cannot write: the file is already closed");
  flushBuffer();
  const char* p = static_cast<const char*>(data);
  while (bytes > 0) {
    ssize_t n = ::pwrite(fd_, p, bytes, static_cast<off_t>(offset));
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("cannot write: " + errnoText(errno));
    }
    p += n;
    offset += static_cast<uint64_t>(n);
    bytes -= static_cast<size_t>(n);
  }
}

void AtomicFileWriter::commit() {
  if (fd_ < 0 || committed_) throw Error(path_.string(), "", "cannot write: the file is already closed");
  flushBuffer();
  int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) {
    int err = errno;
    discard();
    throw Error(path_.string(), "", "cannot write: " + errnoText(err));
  }
  if (std::rename(temp_.c_str(), path_.c_str()) != 0) {
    int err = errno;
    discard();
    throw Error(path_.string(), "", "cannot replace the file: " + errnoText(err));
  }
  temp_.clear();
  committed_ = true;
}

void writeFileAtomic(const std::filesystem::path& path, std::span<const uint8_t> bytes) {
  AtomicFileWriter w(path);
  w.write(bytes);
  w.commit();
}

void writeFileAtomic(const std::filesystem::path& path, std::string_view text) {
  AtomicFileWriter w(path);
  w.write(text);
  w.commit();
}

}  // namespace tendril::io
