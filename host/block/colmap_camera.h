#pragma once
// COLMAP's camera models, shared by the text and the binary model readers so
// that both map a camera to the same OpenCV intrinsics.

#include <filesystem>
#include <string>
#include <vector>

#include "sapmvs/block/block.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/camera.h"

namespace sapmvs {

// A model sapmvs reads; its index in ColmapModels() is COLMAP's model id
// (cameras.bin stores the id, cameras.txt the name).
struct ColmapModel {
  const char* name;
  int num_params;
  const char* layout;
};
const std::vector<ColmapModel>& ColmapModels();

// `params` has model.num_params values in COLMAP's order and pixel convention
// (pixel centres at half-integers); the result is in sapmvs's (OpenCV's).
Intrinsics ColmapIntrinsics(const ColmapModel& model, int width, int height,
                            const std::vector<double>& params);

// Reads the binary model in `dir` (cameras.bin, images.bin, optional
// points3D.bin) into a block in COLMAP's frame; images are looked up in
// `image_dir`. Malformed files throw InputError naming the file and the byte
// offset; counts are checked against the file size before anything is
// allocated.
Block ReadColmapBinaryModel(const std::filesystem::path& dir,
                            const std::filesystem::path& image_dir);

}  // namespace sapmvs
