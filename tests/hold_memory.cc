// A child for timed_child_test: allocates and writes MIB mebibytes, holds
// them for MS milliseconds (long enough for RunTimed to sample them), exits 0.
//
//   hold_memory MIB MS
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <thread>

int main(int argc, char** argv) {
  if (argc != 3) return 2;
  const size_t bytes = std::strtoul(argv[1], nullptr, 10) << 20;
  const int ms = std::atoi(argv[2]);
  auto* p = static_cast<volatile char*>(std::malloc(bytes));
  if (!p) return 3;
  // Written, not zeroed: a page of zeros may be the shared zero page.
  for (size_t i = 0; i < bytes; i += 4096) p[i] = 1;
  std::this_thread::sleep_for(std::chrono::milliseconds(ms));
  std::free(const_cast<char*>(p));
  return 0;
}
