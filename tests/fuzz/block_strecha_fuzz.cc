// Strecha .camera files: input = 0000.jpg.camera [--8<-- 0001.jpg.camera
// [--8<-- 0002.jpg.camera]] in gt_dense_cameras/, images/ beside it.
#include "fuzz_util.h"
#include "sapmvs/block/block_reader.h"

using namespace sapmvs;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const fuzz::fs::path dir = [] {
    const fuzz::fs::path d = fuzz::WorkDir() / "strecha";
    fuzz::fs::create_directories(d / "gt_dense_cameras");
    fuzz::MakeImageStandIns(d / "images");
    return d;
  }();
  const std::vector<std::string> parts = fuzz::Split(data, size, 3);
  for (size_t i = 0; i < 3; ++i) {
    const fuzz::fs::path file =
        dir / "gt_dense_cameras" / ("000" + std::to_string(i) + ".jpg.camera");
    if (i < parts.size()) {
      fuzz::WriteFile(file, parts[i]);
    } else {
      fuzz::fs::remove(file);
    }
  }
  fuzz::Run([&] {
    BlockReadOptions o;
    o.format = BlockFormat::kStrecha;
    o.check_image_sizes = false;
    ReadBlock(dir, o);
  });
  return 0;
}
