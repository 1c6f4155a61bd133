#include "device/roofline_probe.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

#include "device/ncc_scorer.h"
#include "sapmvs/util/error.h"

namespace sapmvs {

namespace {

constexpr char kKernelFile[] = "roofline_probe.cl";

}  // namespace

std::string RooflineProbeOptions::Problem() const {
  if (patch_size < 3 || patch_size > kMaxPatchSize || patch_size % 2 == 0) {
    return "patch_size odd, 3 to " + std::to_string(kMaxPatchSize) +
           " (patch_size = " + std::to_string(patch_size) + ")";
  }
  if (work_group_size < 1) {
    return "work_group_size >= 1 (work_group_size = " + std::to_string(work_group_size) + ")";
  }
  return "";
}

RooflineProbe::RooflineProbe(ClContext& context, const RooflineProbeOptions& options)
    : context_(context), options_(options) {
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("RooflineProbeOptions: expected " + problem);
  const ClProgram& program = context_.Program(
      kKernelFile, NccBuildOptions(options.patch_size, options.work_group_size, 0.0));
  copy_kernel_ = program.Kernel("copy_float4");
  ncc_kernel_ = program.Kernel("ncc_window");
}

ClEvent RooflineProbe::Copy(const ClBuffer& src, ClBuffer& dst, int n) {
  const size_t bytes = static_cast<size_t>(std::max(n, 0)) * sizeof(cl_float4);
  if (n <= 0 || src.size() < bytes || dst.size() < bytes) {
    throw Error("RooflineProbe::Copy: expected 0 < n and buffers of n float4 (n = " +
                std::to_string(n) + ")");
  }
  copy_kernel_.SetArgs(src, dst, cl_int{n});
  return context_.Enqueue(copy_kernel_, NDRange(static_cast<size_t>(n)),
                          NDRange(static_cast<size_t>(options_.work_group_size)));
}

ClEvent RooflineProbe::NccWindows(const ClBuffer& a, const ClBuffer& b, int width, int height,
                                  const ClBuffer& corners, int n, ClBuffer& scores) {
  ncc_kernel_.SetArgs(a, b, cl_int{width}, cl_int{height}, corners, cl_int{n}, scores);
  return context_.Enqueue(ncc_kernel_, NDRange(static_cast<size_t>(n)),
                          NDRange(static_cast<size_t>(options_.work_group_size)));
}

std::vector<float> RooflineProbe::NccWindows(const FloatImageView& a, const FloatImageView& b,
                                             const std::vector<cl_int4>& corners, ClEvent* event) {
  a.layout.Validate("roofline image a");
  b.layout.Validate("roofline image b");
  if (a.layout.width != b.layout.width || a.layout.height != b.layout.height ||
      a.layout.row_pitch != a.layout.width || b.layout.row_pitch != b.layout.width) {
    throw Error("RooflineProbe::NccWindows: expected two images of one size, rows unpadded");
  }
  if (corners.size() > static_cast<size_t>(INT_MAX)) throw Error("roofline batch too large");
  if (corners.empty()) return {};
  const size_t pixels = a.layout.RequiredElements();
  ClBuffer da(context_, pixels * sizeof(float), CL_MEM_READ_ONLY);
  ClBuffer db(context_, pixels * sizeof(float), CL_MEM_READ_ONLY);
  da.Write(a.data, pixels * sizeof(float));
  db.Write(b.data, pixels * sizeof(float));
  ClBuffer dc(context_, corners.size() * sizeof(cl_int4), CL_MEM_READ_ONLY);
  dc.WriteVector(corners);
  ClBuffer ds(context_, corners.size() * sizeof(float), CL_MEM_WRITE_ONLY);
  ClEvent launched =
      NccWindows(da, db, a.layout.width, a.layout.height, dc, static_cast<int>(corners.size()), ds);
  std::vector<float> scores(corners.size());
  ds.ReadVector(&scores);
  if (event != nullptr) *event = std::move(launched);
  return scores;
}

double NccWindowReference(const FloatImageView& a, const FloatImageView& b, const cl_int4& corner,
                          int patch_size) {
  const int w = a.layout.width, h = a.layout.height;
  const int xa = corner.s[0], ya = corner.s[1], xb = corner.s[2], yb = corner.s[3];
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (xa < 0 || ya < 0 || xb < 0 || yb < 0 || xa > w - patch_size || xb > w - patch_size ||
      ya > h - patch_size || yb > h - patch_size) {
    return nan;
  }
  const int n = patch_size * patch_size;
  std::vector<double> va(n), vb(n);
  double mean_a = 0, mean_b = 0;
  for (int r = 0; r < patch_size; ++r) {
    for (int k = 0; k < patch_size; ++k) {
      va[r * patch_size + k] = a.data[static_cast<size_t>(ya + r) * a.layout.row_pitch + xa + k];
      vb[r * patch_size + k] = b.data[static_cast<size_t>(yb + r) * b.layout.row_pitch + xb + k];
      mean_a += va[r * patch_size + k];
      mean_b += vb[r * patch_size + k];
    }
  }
  mean_a /= n;
  mean_b /= n;
  double saa = 0, sbb = 0, sab = 0;
  for (int k = 0; k < n; ++k) {
    saa += (va[k] - mean_a) * (va[k] - mean_a);
    sbb += (vb[k] - mean_b) * (vb[k] - mean_b);
    sab += (va[k] - mean_a) * (vb[k] - mean_b);
  }
  const double min_sum = static_cast<double>(kNccMinVariance) * n;
  if (!(saa >= min_sum && sbb >= min_sum)) return nan;
  return std::clamp(sab / std::sqrt(saa * sbb), -1.0, 1.0);
}

}  // namespace sapmvs
