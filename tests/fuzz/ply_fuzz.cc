// PLY clouds: input = the file.
#include "fuzz_util.h"
#include "sapmvs/io/ply_io.h"

using namespace sapmvs;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const fuzz::fs::path file = fuzz::WorkDir() / "cloud.ply";
  fuzz::WriteFile(file, {reinterpret_cast<const char*>(data), size});
  fuzz::Run([&] { ReadPly(file); });
  return 0;
}
