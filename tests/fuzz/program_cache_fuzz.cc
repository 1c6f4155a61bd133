// Program cache entries: input = the entry file of one key. Load takes any
// bytes from the cache folder and must refuse all but a whole entry of its
// key, without throwing and without reading more than the file announces.
#include <cstdlib>

#include "device/program_binary_cache.h"
#include "fuzz_util.h"

using namespace sapmvs;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const ProgramBinaryCache cache = [] {
    fuzz::fs::create_directories(fuzz::WorkDir() / "programs");
    return ProgramBinaryCache(fuzz::WorkDir() / "programs");
  }();
  fuzz::WriteFile(cache.EntryPath(fuzz::kProgramCacheKey),
                  {reinterpret_cast<const char*>(data), size});
  fuzz::Run([&] {
    const auto binary = cache.Load(fuzz::kProgramCacheKey);
    if (binary && (binary->empty() || binary->size() >= size)) std::abort();
  });
  return 0;
}
