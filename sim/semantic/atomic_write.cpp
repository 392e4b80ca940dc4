#include "atomic_write.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace plr::sim {

std::string write_atomically(const std::filesystem::path& file, const std::string& content) {
  const auto dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  const std::string tmp = (dir / ("." + file.filename().string() + ".XXXXXX")).string();
  std::string name = tmp;
  const int fd = mkstemp(name.data());
  if (fd < 0) return std::string("cannot create a temporary file: ") + std::strerror(errno);
  std::size_t done = 0;
  while (done < content.size()) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = std::strerror(errno);
      ::close(fd);
      ::unlink(name.c_str());
      return "write failed: " + why;
    }
    done += static_cast<std::size_t>(n);
  }
  // mkstemp creates 0600; strategy files are ordinary documents.
  if (::fchmod(fd, 0644) != 0 || ::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(name.c_str());
    return "cannot flush the temporary file: " + why;
  }
  if (std::rename(name.c_str(), file.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(name.c_str());
    return "cannot rename the temporary file: " + why;
  }
  if (const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY); dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
  return {};
}

}  // namespace plr::sim
