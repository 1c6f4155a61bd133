// PMVS folder: input = txt/00000000.txt [--8<-- 00000001.txt [--8<-- 00000002.txt
// [--8<-- sapmvs_frame.json]]]. The PMVS reader takes image sizes from the
// image headers, so visualize/ holds real (tiny) PNGs.
#include <opencv2/imgcodecs.hpp>

#include "fuzz_util.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/export_frame.h"

using namespace sapmvs;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const fuzz::fs::path dir = [] {
    const fuzz::fs::path d = fuzz::WorkDir() / "pmvs";
    fuzz::fs::create_directories(d / "txt");
    fuzz::fs::create_directories(d / "visualize");
    const cv::Mat pixels(6, 8, CV_8UC3, cv::Scalar(10, 20, 30));
    for (int i = 0; i < 3; ++i) {
      cv::imwrite((d / "visualize" / ("0000000" + std::to_string(i) + ".png")).string(), pixels);
    }
    return d;
  }();
  const std::vector<std::string> parts = fuzz::Split(data, size, 4);
  for (size_t i = 0; i < 3; ++i) {
    const fuzz::fs::path file = dir / "txt" / ("0000000" + std::to_string(i) + ".txt");
    if (i < parts.size()) {
      fuzz::WriteFile(file, parts[i]);
    } else {
      fuzz::fs::remove(file);
    }
  }
  if (parts.size() > 3) {
    fuzz::WriteFile(dir / kExportFrameFile, parts[3]);
  } else {
    fuzz::fs::remove(dir / kExportFrameFile);
  }
  fuzz::Run([&] {
    BlockReadOptions o;
    o.format = BlockFormat::kPmvs;
    o.check_image_sizes = false;
    ReadBlock(dir, o);
  });
  return 0;
}
