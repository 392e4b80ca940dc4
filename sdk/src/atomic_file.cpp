#include <plr/atomic_file.hpp>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace plr {

Status write_file_atomically(const std::string& path, std::string_view content) {
  const auto fail = [&](const char* what, int error) {
    return make_error(PLR_ERR_INTERNAL, path + ": " + what + ": " + std::strerror(error));
  };
  const std::filesystem::path file(path);
  if (!file.has_filename()) return make_error(PLR_ERR_INVALID, path + ": not a file name");
  const std::string dir = file.has_parent_path() ? file.parent_path().string() : ".";
  std::string temp = dir + "/." + file.filename().string() + ".XXXXXX";
  const int fd = ::mkostemp(temp.data(), O_CLOEXEC);
  if (fd < 0) return fail("cannot create a temporary file", errno);
  const auto abandon = [&](const char* what) {
    const int error = errno;
    ::close(fd);
    ::unlink(temp.c_str());
    return fail(what, error);
  };
  for (std::size_t done = 0; done < content.size();) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return abandon("cannot write");
    done += static_cast<std::size_t>(n);
  }
  // mkostemp makes the file 0600; what PLR writes (reports, worlds,
  // strategies) is an ordinary document.
  if (::fchmod(fd, 0644) != 0) return abandon("cannot set the mode");
  if (::fsync(fd) != 0) return abandon("cannot flush");
  if (::close(fd) != 0) {
    const int error = errno;
    ::unlink(temp.c_str());
    return fail("cannot flush", error);
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const int error = errno;
    ::unlink(temp.c_str());
    return fail("cannot replace", error);
  }
  // The rename reaches the disk only with its folder.
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd < 0) return fail("cannot open its folder", errno);
  const int synced = ::fsync(dfd);
  const int error = errno;
  ::close(dfd);
  if (synced != 0) return fail("cannot flush its folder", error);
  return {};
}

}  // namespace plr
