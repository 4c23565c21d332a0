#include <mpm/io/atomic_file.h>

#include <mpm/core/error.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

#include <fcntl.h>
#include <signal.h>
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

void write_whole_file(const std::filesystem::path& path, std::string_view content) {
  const auto fail = [&](const char* what) {
    throw IoError(std::string(what) + " '" + path.string() + "': " + std::strerror(errno));
  };
  // POSIX I/O rather than a stream: errno gives the reason (ENOSPC, EACCES, ...).
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
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
}

void write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  AtomicFile file(path);
  try {
    write_whole_file(file.temp_path(), content);
  } catch (const IoError& e) {
    throw IoError("cannot write '" + path.string() + "': " + e.what());
  }
  file.commit();
}

std::size_t remove_stale_temporaries(const std::filesystem::path& folder) {
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error)) return 0;
  std::size_t removed = 0;
  for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
    const std::string name = entry.path().filename().string();
    const std::size_t mark = name.rfind(".tmp-");
    if (mark == std::string::npos || !entry.is_regular_file(error)) continue;
    const std::string digits = name.substr(mark + 5);
    if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const auto pid = static_cast<pid_t>(std::stol(digits));
    // kill(pid, 0) probes without signalling: ESRCH means no such process, so nobody writes it.
    if (pid == ::getpid() || ::kill(pid, 0) == 0 || errno != ESRCH) continue;
    if (std::filesystem::remove(entry.path(), error)) ++removed;
  }
  return removed;
}

}  // namespace mpm::io
