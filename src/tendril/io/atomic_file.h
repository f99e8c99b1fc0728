// Writing files so that nothing already saved is harmed: the bytes go to a temporary file in
// the same directory, which replaces the target by rename() only once everything is written
// and closed. On any failure the temporary is removed, the target is left as it was, and an
// Error(path, "", reason) is thrown. Parent directories are not created: a missing directory
// is an Error naming the path.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>

namespace tendril::io {

// Streams bytes into a temporary beside `path`; commit() makes them the file's content.
// Destroying a writer that was not committed removes the temporary.
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(std::filesystem::path path);
  ~AtomicFileWriter();
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  void write(const void* data, size_t bytes);
  void write(std::string_view text) { write(text.data(), text.size()); }
  void write(std::span<const uint8_t> bytes) { write(bytes.data(), bytes.size()); }
  // Writes `bytes` at `offset` of the file (after flushing what is buffered), for headers whose
  // content is known only at the end; the sequential position and bytesWritten() are unchanged.
  void writeAt(uint64_t offset, const void* data, size_t bytes);
  // Flushes, closes and renames the temporary over the target.
  void commit();

  const std::filesystem::path& path() const { return path_; }
  uint64_t bytesWritten() const { return written_; }

 private:
  void flushBuffer();
  [[noreturn]] void fail(const std::string& what);
  void discard() noexcept;

  std::filesystem::path path_;
  std::filesystem::path temp_;
  int fd_ = -1;
  bool committed_ = false;
  uint64_t written_ = 0;
  std::unique_ptr<char[]> buffer_;
  size_t buffered_ = 0;
};

// Throws the Error a writer for `path` would throw for a missing directory or a path that
// names a directory; writers call it before long work so that the user hears at once.
void checkOutputPath(const std::filesystem::path& path);

void writeFileAtomic(const std::filesystem::path& path, std::span<const uint8_t> bytes);
void writeFileAtomic(const std::filesystem::path& path, std::string_view text);

}  // namespace tendril::io
