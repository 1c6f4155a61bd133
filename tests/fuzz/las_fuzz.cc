// LAS clouds: input = the file.
#include "fuzz_util.h"
#include "sapmvs/io/las_io.h"

using namespace sapmvs;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const fuzz::fs::path file = fuzz::WorkDir() / "cloud.las";
  fuzz::WriteFile(file, {reinterpret_cast<const char*>(data), size});
  fuzz::Run([&] { ReadLas(file); });
  return 0;
}
