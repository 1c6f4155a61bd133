#include "device/bilinear_sampler.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>
#include <string>

namespace sapmvs {
namespace {

constexpr char kKernelFile[] = "bilinear_sample.cl";
constexpr char kKernelName[] = "bilinear_sample";

// The buffer upload reinterprets the vector as float2[].
static_assert(sizeof(Eigen::Vector2f) == 2 * sizeof(float), "Vector2f must be two packed floats");

void CheckBatchSize(size_t num_points) {
  if (num_points > static_cast<size_t>(INT_MAX)) {
    throw Error("bilinear sampling batch of " + std::to_string(num_points) +
                " points exceeds the kernel's limit of " + std::to_string(INT_MAX));
  }
}

void CheckBufferHolds(const ClBuffer& buffer, const char* what, size_t bytes) {
  if (buffer.get() == nullptr || buffer.size() < bytes) {
    throw Error(std::string("bilinear sampling: ") + what + " buffer holds " +
                std::to_string(buffer.get() ? buffer.size() : 0) + " bytes, needs " +
                std::to_string(bytes));
  }
}

}  // namespace

bool BilinearSamplerOptions::Check() const { return work_group_size >= 1; }

BilinearSampler::BilinearSampler(ClContext& context, const BilinearSamplerOptions& options)
    : context_(context), options_(options) {
  if (!options.Check()) {
    throw Error("BilinearSamplerOptions: work_group_size must be >= 1, got " +
                std::to_string(options.work_group_size));
  }
  const BuildOptions defines = BuildOptions().Define("WORK_GROUP_SIZE", options.work_group_size);
  kernel_ = context_.Program(kKernelFile, defines).Kernel(kKernelName);
}

std::vector<float> BilinearSampler::Sample(const FloatImageView& image,
                                           const std::vector<Eigen::Vector2f>& points) {
  image.layout.Validate("bilinear sampling image");
  if (image.data == nullptr) throw Error("bilinear sampling image has no pixel data");
  CheckBatchSize(points.size());
  if (points.empty()) return {};

  const size_t image_bytes = image.layout.RequiredElements() * sizeof(float);
  ClBuffer image_buffer(context_, image_bytes, CL_MEM_READ_ONLY);
  image_buffer.Write(image.data, image_bytes);
  ClBuffer point_buffer(context_, points.size() * sizeof(Eigen::Vector2f), CL_MEM_READ_ONLY);
  point_buffer.Write(points.data(), points.size() * sizeof(Eigen::Vector2f));
  ClBuffer value_buffer(context_, points.size() * sizeof(float), CL_MEM_WRITE_ONLY);

  Sample(image_buffer, image.layout, point_buffer, static_cast<int>(points.size()), value_buffer);
  // The blocking read on the in-order queue waits for the kernel.
  std::vector<float> values(points.size());
  value_buffer.ReadVector(&values);
  return values;
}

ClEvent BilinearSampler::Sample(const ClBuffer& image, const ImageLayout& layout,
                                const ClBuffer& points, int num_points, ClBuffer& values) {
  layout.Validate("bilinear sampling image");
  if (num_points < 0) {
    throw Error("bilinear sampling batch size is negative (" + std::to_string(num_points) + ")");
  }
  CheckBufferHolds(image, "image", layout.RequiredElements() * sizeof(float));
  if (num_points == 0) return ClEvent();
  CheckBufferHolds(points, "points", static_cast<size_t>(num_points) * 2 * sizeof(float));
  CheckBufferHolds(values, "values", static_cast<size_t>(num_points) * sizeof(float));

  kernel_.SetArgs(points, cl_int{num_points}, image, cl_int{layout.width}, cl_int{layout.height},
                  cl_int{layout.row_pitch}, values);
  const size_t group = static_cast<size_t>(options_.work_group_size);
  return context_.Enqueue(kernel_, NDRange(static_cast<size_t>(num_points)), NDRange(group));
}

}  // namespace sapmvs
