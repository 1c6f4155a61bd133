#pragma once
// A run's images at the level it matches, decoded once. Every group decodes
// its images (references and views) when it loads, and its references
// again for the points' colours; neighbouring groups share most of their
// images, so a block's image was decoded, undistorted and halved some 6 to
// 8 times (`small`: 10 images, 80 decodes, a sixth of the run). The store
// keeps each image's pixels at the level as a raw file beside the
// checkpoints, which every later read maps back at the cost of a copy. On
// disk rather than in memory: a group's peak, which the plan budgets, stays
// what it was.
#include <filesystem>
#include <opencv2/core.hpp>

#include "sapmvs/block/block.h"

namespace sapmvs {

class LevelImageStore {
 public:
  // Keeps the images under `dir` (made when first needed); an empty `dir`
  // keeps none: each read decodes. A copy is kept only while the disk
  // keeps `min_free_bytes` free after it (by default 1 GiB and a tenth of
  // the disk): on a block of thousands of large images the copies could
  // otherwise take the room the outputs need (1,000 images of 20 MP at
  // level 1 are 15 GB of them).
  explicit LevelImageStore(std::filesystem::path dir = {}, double min_free_bytes = -1);

  // The 8-bit BGR pixels of `image`, undistorted and at pyramid `level`, of
  // size `width` x `height` (its pinhole camera scaled to the level), as
  // ResampleToLevel(LoadUndistorted(image).pixels, ...) gives them. From the
  // kept copy when one was made from the same file (size and modification
  // time) at this level and size; else decoded, and a copy kept. A copy
  // that cannot be written (a full disk) is skipped, not an error: the next
  // read decodes again. `keep` false: a decoded image is not kept (its last
  // read). Throws sapmvs::Error as LoadImage does. Threads may read
  // different images at once, and processes (mpirun's ranks) the same.
  cv::Mat Load(const BlockImage& image, int level, int width, int height, bool keep = true) const;

  // Removes the kept copies and their folder; nothing when there are none.
  void Clear() const;

 private:
  std::filesystem::path dir_;
  double min_free_bytes_;
};

// `store`, or where it is null a store that keeps nothing: for the callers
// that take an optional store, whose every read then decodes.
const LevelImageStore& StoreOrNone(const LevelImageStore* store);

}  // namespace sapmvs
