#include <mpm/io/atomic_file.h>

#include <mpm/core/error.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

#include <fcntl.h>
#include <unistd.h>

namespace mpm::io {

AtomicFile::AtomicFile(std::filesystem::path target)
    : target_(std::move(target)), temp_(target_.string() + ".tmp-" + std::to_string(::getpid())) {}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  std::error_code ignored;  // nothing may throw here; a missing temp file is fine
  std::filesystem::remove(temp_, ignored);
}

void AtomicFile::commit() {
  std::error_code error;
  std::filesystem::rename(temp_, target_, error);
  if (error)
    throw IoError("cannot write '" + target_.string() + "': renaming '" + temp_.string() +
                  "' failed: " + error.message());
  committed_ = true;
}

void write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  AtomicFile file(path);
  const auto fail = [&](const char* what) {
    throw IoError("cannot write '" + path.string() + "': " + what + " '" + file.temp_path().string() +
                  "': " + std::strerror(errno));
  };
  // POSIX I/O rather than a stream: errno gives the reason (ENOSPC, EACCES, ...).
  const int fd = ::open(file.temp_path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail("cannot create");
  std::size_t written = 0;
  while (written < content.size()) {
    const ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int saved = errno;
      ::close(fd);
      errno = saved;
      fail("cannot write");
    }
    written += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0) fail("cannot close");
  file.commit();
}

}  // namespace mpm::io
