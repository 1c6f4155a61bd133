// block.yaml and its orientation file: input = block.yaml [--8<-- orientation.txt].
#include "fuzz_util.h"
#include "sapmvs/block/block_reader.h"

using namespace sapmvs;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const fuzz::fs::path dir = [] {
    const fuzz::fs::path d = fuzz::WorkDir() / "yaml";
    fuzz::MakeImageStandIns(d / "images");
    return d;
  }();
  const std::vector<std::string> parts = fuzz::Split(data, size, 2);
  fuzz::WriteFile(dir / "block.yaml", parts[0]);
  fuzz::WriteFile(dir / "orientation.txt", parts.size() > 1 ? parts[1] : "");
  fuzz::Run([&] {
    BlockReadOptions o;
    o.format = BlockFormat::kYaml;
    o.check_image_sizes = false;
    ReadBlock(dir / "block.yaml", o);
  });
  return 0;
}
