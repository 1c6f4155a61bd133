// OpenSfM: input = opensfm/reconstruction.json, images/ beside opensfm/.
#include "fuzz_util.h"
#include "sapmvs/block/block_reader.h"

using namespace sapmvs;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const fuzz::fs::path dir = [] {
    const fuzz::fs::path d = fuzz::WorkDir() / "opensfm";
    fuzz::fs::create_directories(d / "opensfm");
    fuzz::MakeImageStandIns(d / "images");
    return d;
  }();
  const fuzz::fs::path json = dir / "opensfm" / "reconstruction.json";
  fuzz::WriteFile(json, {reinterpret_cast<const char*>(data), size});
  fuzz::Run([&] {
    BlockReadOptions o;
    o.format = BlockFormat::kOpenSfm;
    o.check_image_sizes = false;
    ReadBlock(json, o);
  });
  return 0;
}
