// LD_PRELOAD module for the CLI tests: a disk that fills up under one folder
// only. write(2) to a file whose path starts with $SAPMVS_FULL_DISK_DIR
// stores at most $SAPMVS_FULL_DISK_BYTES bytes of the file, then fails with
// ENOSPC, as a full disk does. Files elsewhere (the OpenCL driver's kernel
// cache and temporaries) are untouched, which RLIMIT_FSIZE cannot do.
#include <dlfcn.h>
#include <errno.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

extern "C" ssize_t write(int fd, const void* buf, size_t n) {
  using WriteFn = ssize_t (*)(int, const void*, size_t);
  static const WriteFn real = reinterpret_cast<WriteFn>(dlsym(RTLD_NEXT, "write"));
  const char* dir = std::getenv("SAPMVS_FULL_DISK_DIR");
  const char* bytes = std::getenv("SAPMVS_FULL_DISK_BYTES");
  if (dir == nullptr || bytes == nullptr || fd <= 2) return real(fd, buf, n);
  char link[64], path[4096];
  std::snprintf(link, sizeof(link), "/proc/self/fd/%d", fd);
  const ssize_t len = readlink(link, path, sizeof(path) - 1);
  if (len <= 0) return real(fd, buf, n);
  path[len] = '\0';
  if (std::strncmp(path, dir, std::strlen(dir)) != 0) return real(fd, buf, n);
  const off_t limit = std::atol(bytes);
  const off_t pos = lseek(fd, 0, SEEK_CUR);
  if (pos < 0 || pos + static_cast<off_t>(n) <= limit) return real(fd, buf, n);
  if (pos < limit) return real(fd, buf, static_cast<size_t>(limit - pos));  // what fits
  errno = ENOSPC;
  return -1;
}
