#include "match/float_image.h"

#include <string>

#include "sapmvs/util/error.h"

namespace sapmvs {

size_t ImageLayout::RequiredElements() const {
  if (width <= 0 || height <= 0) return 0;
  return static_cast<size_t>(height - 1) * static_cast<size_t>(row_pitch) +
         static_cast<size_t>(width);
}

void ImageLayout::Validate(const char* what) const {
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  if (width <= 0 || height <= 0) {
    throw Error(std::string(what) + " is empty (" + size + "); expected at least 1x1 pixels");
  }
  if (width > kMaxImageSide || height > kMaxImageSide) {
    throw Error(std::string(what) + " of " + size +
                " pixels exceeds the float32 kernels' limit of " + std::to_string(kMaxImageSide) +
                " pixels per side");
  }
  if (row_pitch < width) {
    throw Error(std::string(what) + " row pitch " + std::to_string(row_pitch) +
                " is smaller than its width " + std::to_string(width));
  }
}

double BilinearSampleReference(const FloatImageView& image, double x, double y) {
  const ImageLayout& layout = image.layout;
  layout.Validate("bilinear reference image");
  if (image.data == nullptr) throw Error("bilinear reference image has no pixel data");
  return BilinearSampleUnchecked(image, x, y);
}

std::vector<double> BilinearSampleReference(const FloatImageView& image,
                                            const std::vector<Eigen::Vector2f>& points) {
  image.layout.Validate("bilinear reference image");
  std::vector<double> values;
  values.reserve(points.size());
  for (const Eigen::Vector2f& p : points)
    values.push_back(BilinearSampleReference(image, p.x(), p.y()));
  return values;
}

}  // namespace sapmvs
