// PMVS/CMVS folders as VisualSFM and Bundler2PMVS write them:
//   txt/NNNNNNNN.txt   "CONTOUR" then the 3x4 projection matrix (3 rows)
//   visualize/NNNNNNNN.jpg (or .ppm/.png), already undistorted
// The image size is not in the text file: it comes from the image header.
// A folder `sapmvs export` wrote is in the block's local frame; its side file
// (export_frame.h) puts the cameras back into the world frame.

#include <Eigen/LU>
#include <algorithm>
#include <cctype>

#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/export_frame.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/util/error.h"
#include "util/text_lines.h"

namespace sapmvs {
namespace fs = std::filesystem;

Block ReadPmvsBlock(const fs::path& given, const BlockReadOptions& options) {
  const fs::path root = fs::is_regular_file(given) ? given.parent_path().parent_path() : given;
  const fs::path txt = root / "txt";
  if (!fs::is_directory(txt)) throw Error(root.string() + ": no txt/ folder (PMVS layout)");
  const std::optional<ExportFrame> frame = ReadExportFrame(root);
  const fs::path image_dir = options.image_dir.empty() ? root / "visualize" : options.image_dir;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(txt)) {
    const std::string stem = e.path().stem().string();
    if (e.path().extension() == ".txt" && stem.size() == 8 &&
        std::all_of(stem.begin(), stem.end(), [](char c) { return std::isdigit(c); })) {
      files.push_back(e.path());
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw Error(txt.string() + ": no NNNNNNNN.txt camera files");

  Block block;
  block.frame_note = "PMVS frame (as given by the projection matrices)";
  // Files whose P has a left 3x3 block of negative or positive determinant.
  std::vector<fs::path> negative, positive;
  for (const fs::path& file : files) {
    TextLines lines(file);
    std::vector<std::string> t;
    if (!lines.Next(&t) || t.size() != 1 || t[0] != "CONTOUR") {
      throw lines.Fail("expected the header line 'CONTOUR'");
    }
    Eigen::Matrix<double, 3, 4> p;
    for (int r = 0; r < 3; ++r) {
      if (!lines.Next(&t))
        throw lines.Fail("unexpected end of file, expected row " + std::to_string(r + 1) +
                         " of the 3x4 matrix P");
      lines.ExpectCount(t, 4, "row " + std::to_string(r + 1) + " of P: 4 numbers");
      for (int c = 0; c < 4; ++c)
        p(r, c) = lines.Double(t[c], "P" + std::to_string(r + 1) + std::to_string(c + 1));
    }
    if (lines.Next(&t)) throw lines.Fail("unexpected extra content after the 3x4 matrix");
    (Eigen::Matrix3d(p.leftCols<3>()).determinant() < 0 ? negative : positive).push_back(file);
    BlockImage im;
    im.name = file.stem().string();
    im.camera_name = im.name;
    im.path = FindImageFile(image_dir, im.name);
    if (im.path.empty()) {
      throw InputError(file.string(), 0, "no image " + im.name + ".* in " + image_dir.string());
    }
    const ImageSize size = ReadImageSize(im.path);
    try {
      im.camera = Camera::FromProjectionMatrix(p, size.width, size.height);
    } catch (const Error& e) {
      throw InputError(file.string(), 2, e.what());
    }
    block.images.push_back(std::move(im));
  }
  // P's scale is arbitrary and may be negative (VisualSFM), which makes the
  // determinant negative; the reader then flips P. But one camera of another
  // sign than the rest has a negative focal length (a mirrored camera) or a
  // flipped P, and reading it as given would turn it to look away.
  if (!negative.empty() && !positive.empty()) {
    const bool few_negative = negative.size() <= positive.size();
    const std::vector<fs::path>& odd = few_negative ? negative : positive;
    const std::vector<fs::path>& rest = few_negative ? positive : negative;
    throw InputError(
        odd.front().string(), 2,
        std::string("negative focal length or P of the wrong sign: det of P's left 3x3 block is ") +
            (few_negative ? "negative" : "positive") + ", but " +
            (few_negative ? "positive" : "negative") + " for " + rest.front().filename().string() +
            (rest.size() > 1 ? " and " + std::to_string(rest.size() - 1) + " more" : "") +
            " (expected P = s K [R, t] with fx, fy > 0 and one sign of s for all cameras)");
  }
  if (frame) ApplyExportFrame(*frame, root, "pmvs", &block);
  return block;
}

}  // namespace sapmvs
