#include "ncc_scorer.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <climits>
#include <cmath>
#include <iostream>
#include <limits>
#include <string>

namespace sapmvs {
namespace {

constexpr char kKernelFile[] = "ncc_score.cl";
constexpr char kScoreKernel[] = "ncc_score";
constexpr char kProbeKernel[] = "ncc_sample_probe";

// Twin of NCC_MIN_AXIS_LENGTH in kernels/ncc_score.cl: a kernel-internal
// geometric guard, not a tunable, so it is not passed as -D.
constexpr double kNccMinAxisLength = 1e-3;
// How far from unit length a patch normal may be; the kernel does not
// renormalise, so a sloppy normal would silently shear the grid.
constexpr double kUnitNormalTolerance = 1e-3;

// The first failing condition, or "" when the options are usable.
std::string OptionsProblem(const NccScorerOptions& o) {
  const std::string got = " (patch_size = " + std::to_string(o.patch_size) + ")";
  if (o.patch_size < 3) return "patch_size >= 3" + got;
  if (o.patch_size > kMaxPatchSize) {
    return "patch_size <= kMaxPatchSize = " + std::to_string(kMaxPatchSize) + got;
  }
  if (o.patch_size % 2 != 1) return "patch_size is odd" + got;
  if (o.work_group_size < 1) {
    return "work_group_size >= 1 (work_group_size = " + std::to_string(o.work_group_size) + ")";
  }
  if (!(std::isfinite(o.sigma_color) && o.sigma_color >= 0.0)) {
    return "sigma_color finite and >= 0 (sigma_color = " + std::to_string(o.sigma_color) + ")";
  }
  return "";
}

cl_float4 Float4(double x, double y, double z, double w) {
  cl_float4 v;
  v.s[0] = static_cast<float>(x);
  v.s[1] = static_cast<float>(y);
  v.s[2] = static_cast<float>(z);
  v.s[3] = static_cast<float>(w);
  return v;
}

Eigen::Vector3d Xyz(const cl_float4& v) { return {v.s[0], v.s[1], v.s[2]}; }
Eigen::Vector4d Xyzw(const cl_float4& v) { return {v.s[0], v.s[1], v.s[2], v.s[3]}; }

bool AllFinite(const cl_float4& v, int n) {
  for (int k = 0; k < n; ++k) {
    if (!std::isfinite(v.s[k])) return false;
  }
  return true;
}

// Signed distance of (x, y) to the edge of [0, w - 1] x [0, h - 1]: positive
// inside, negative outside.
double BorderDistance(const ImageLayout& layout, double x, double y) {
  return std::min({x, y, (layout.width - 1) - x, (layout.height - 1) - y});
}

}  // namespace

NccCamera MakeNccCamera(const Camera& local_camera, const char* what) {
  if (!local_camera.intrinsics().distortion.IsZero()) {
    throw Error(std::string(what) +
                " has lens distortion; the NCC kernel needs the pinhole camera " +
                "of the undistorted image (Camera::Pinhole)");
  }
  const Eigen::Matrix<double, 3, 4> p = local_camera.ProjectionMatrix();
  const Eigen::Matrix3d& r = local_camera.rotation();
  const Eigen::Vector3d& c = local_camera.center();
  NccCamera camera;
  for (int row = 0; row < 3; ++row)
    camera.p[row] = Float4(p(row, 0), p(row, 1), p(row, 2), p(row, 3));
  camera.x_axis = Float4(r(0, 0), r(0, 1), r(0, 2), 0.0);
  camera.y_axis = Float4(r(1, 0), r(1, 1), r(1, 2), 0.0);
  camera.center = Float4(c.x(), c.y(), c.z(), local_camera.intrinsics().MeanFocal());
  return camera;
}

NccPatch MakeNccPatch(const Eigen::Vector3d& center, const Eigen::Vector3d& normal, int reference) {
  NccPatch patch;
  patch.center = Float4(center.x(), center.y(), center.z(), 0.0);
  patch.normal = Float4(normal.x(), normal.y(), normal.z(), 0.0);
  patch.reference = reference;
  return patch;
}

bool NccScorerOptions::Check() const {
  const std::string problem = OptionsProblem(*this);
  if (problem.empty()) return true;
  std::cerr << "NccScorerOptions: check failed: " << problem << "\n";
  return false;
}

void NccGroup::Validate() const {
  if (images.empty()) throw Error("NCC group has no images");
  if (images.size() != cameras.size()) {
    throw Error("NCC group has " + std::to_string(images.size()) + " images but " +
                std::to_string(cameras.size()) + " cameras");
  }
  if (images.size() > static_cast<size_t>(INT_MAX)) throw Error("NCC group has too many images");
  for (size_t i = 0; i < images.size(); ++i) {
    const std::string name = "NCC group image " + std::to_string(i);
    images[i].layout.Validate(name.c_str());
    if (images[i].data == nullptr) throw Error(name + " has no pixel data");
    const NccCamera& camera = cameras[i];
    bool finite =
        AllFinite(camera.x_axis, 3) && AllFinite(camera.y_axis, 3) && AllFinite(camera.center, 4);
    for (const cl_float4& row : camera.p) finite = finite && AllFinite(row, 4);
    if (!finite) throw Error(name + ": camera has a non-finite entry");
    if (!(camera.center.s[3] > 0.0f)) {
      throw Error(name + ": camera focal length " + std::to_string(camera.center.s[3]) +
                  " is not positive");
    }
  }
}

void ValidateNccBatch(const std::vector<NccPatch>& patches, const std::vector<NccPair>& pairs,
                      int num_images) {
  if (patches.size() > static_cast<size_t>(INT_MAX) ||
      pairs.size() > static_cast<size_t>(INT_MAX)) {
    throw Error("NCC batch exceeds the kernel's limit of " + std::to_string(INT_MAX) + " items");
  }
  for (size_t i = 0; i < patches.size(); ++i) {
    const NccPatch& patch = patches[i];
    const std::string name = "NCC patch " + std::to_string(i);
    if (patch.reference < 0 || patch.reference >= num_images) {
      throw Error(name + ": reference image " + std::to_string(patch.reference) +
                  " is not in the group of " + std::to_string(num_images) + " images");
    }
    if (!AllFinite(patch.center, 3) || !AllFinite(patch.normal, 3)) {
      throw Error(name + " has a non-finite centre or normal");
    }
    const double norm = Xyz(patch.normal).norm();
    if (!(std::abs(norm - 1.0) <= kUnitNormalTolerance)) {
      throw Error(name + ": normal has length " + std::to_string(norm) + ", expected 1");
    }
  }
  for (size_t i = 0; i < pairs.size(); ++i) {
    const NccPair& pair = pairs[i];
    const std::string name = "NCC pair " + std::to_string(i);
    if (pair.patch < 0 || static_cast<size_t>(pair.patch) >= patches.size()) {
      throw Error(name + ": patch " + std::to_string(pair.patch) + " is not in the batch of " +
                  std::to_string(patches.size()) + " patches");
    }
    if (pair.view < 0 || pair.view >= num_images) {
      throw Error(name + ": view " + std::to_string(pair.view) + " is not in the group of " +
                  std::to_string(num_images) + " images");
    }
  }
}

BuildOptions NccBuildOptions(int patch_size, int work_group_size, double sigma_color) {
  BuildOptions defines;
  defines.Define("NCC_MIN_VARIANCE", kNccMinVariance)
      .Define("NCC_SIGMA_COLOR", static_cast<float>(sigma_color))
      .Define("PATCH_SIZE", patch_size)
      .Define("WORK_GROUP_SIZE", work_group_size);
  return defines;
}

NccScorer::NccScorer(ClContext& context, const NccScorerOptions& options)
    : context_(context), options_(options) {
  const std::string problem = OptionsProblem(options);
  if (!problem.empty()) throw Error("NccScorerOptions: expected " + problem);
  const ClProgram& program = context_.Program(
      kKernelFile,
      NccBuildOptions(options.patch_size, options.work_group_size, options.sigma_color));
  score_kernel_ = program.Kernel(kScoreKernel);
  probe_kernel_ = program.Kernel(kProbeKernel);
}

NccDeviceGroup UploadNccGroup(ClContext& context, const NccGroup& group) {
  group.Validate();
  // Pack every image into one buffer: one argument however many images, and
  // the int4 table addresses them (offsets in elements).
  std::vector<cl_int4> table(group.images.size());
  size_t total = 0;
  for (size_t i = 0; i < group.images.size(); ++i) {
    const ImageLayout& layout = group.images[i].layout;
    if (total > static_cast<size_t>(INT_MAX) - layout.RequiredElements()) {
      throw Error("NCC group images exceed " + std::to_string(INT_MAX) +
                  " pixels in all, the kernel's offset limit");
    }
    table[i].s[0] = static_cast<cl_int>(total);
    table[i].s[1] = layout.width;
    table[i].s[2] = layout.height;
    table[i].s[3] = layout.row_pitch;
    total += layout.RequiredElements();
  }
  ClBuffer images(context, total * sizeof(float), CL_MEM_READ_ONLY);
  for (size_t i = 0; i < group.images.size(); ++i) {
    images.Write(group.images[i].data, group.images[i].layout.RequiredElements() * sizeof(float),
                 static_cast<size_t>(table[i].s[0]) * sizeof(float));
  }
  ClBuffer image_table(context, table.size() * sizeof(cl_int4), CL_MEM_READ_ONLY);
  image_table.WriteVector(table);
  ClBuffer cameras(context, group.cameras.size() * sizeof(NccCamera), CL_MEM_READ_ONLY);
  cameras.WriteVector(group.cameras);
  NccDeviceGroup out;
  out.images = std::move(images);
  out.image_table = std::move(image_table);
  out.cameras = std::move(cameras);
  out.num_images = static_cast<int>(group.images.size());
  return out;
}

void NccScorer::SetGroup(const NccGroup& group) {
  // Assigned only once everything is uploaded, so a failure keeps the old group.
  group_ = std::make_shared<const NccDeviceGroup>(UploadNccGroup(context_, group));
}

void NccScorer::UseGroup(std::shared_ptr<const NccDeviceGroup> group) {
  if (!group || group->num_images == 0) throw Error("NccScorer::UseGroup: no images");
  group_ = std::move(group);
}

std::vector<float> NccScorer::Score(const std::vector<NccPatch>& patches,
                                    const std::vector<NccPair>& pairs, ClEvent* event) {
  if (num_images() == 0) throw Error("NccScorer::Score called before SetGroup");
  ValidateNccBatch(patches, pairs, group_->num_images);
  if (pairs.empty()) return {};

  ClBuffer patch_buffer(context_, patches.size() * sizeof(NccPatch), CL_MEM_READ_ONLY);
  patch_buffer.WriteVector(patches);
  ClBuffer pair_buffer(context_, pairs.size() * sizeof(NccPair), CL_MEM_READ_ONLY);
  pair_buffer.WriteVector(pairs);
  ClBuffer score_buffer(context_, pairs.size() * sizeof(float), CL_MEM_WRITE_ONLY);

  const cl_int num_pairs = static_cast<cl_int>(pairs.size());
  score_kernel_.SetArgs(group_->images, group_->image_table, group_->cameras,
                        cl_int{group_->num_images}, patch_buffer,
                        static_cast<cl_int>(patches.size()), pair_buffer, num_pairs, score_buffer);
  ClEvent launched = context_.Enqueue(score_kernel_, NDRange(pairs.size()),
                                      NDRange(static_cast<size_t>(options_.work_group_size)));
  // The blocking read on the in-order queue waits for the kernel.
  std::vector<float> scores(pairs.size());
  score_buffer.ReadVector(&scores);
  if (event != nullptr) *event = std::move(launched);
  return scores;
}

std::vector<float> NccScorer::ProbeSamples(int image, const std::vector<Eigen::Vector2f>& points) {
  if (image < 0 || image >= num_images()) {
    throw Error("NCC probe image " + std::to_string(image) + " is not in the group of " +
                std::to_string(num_images()) + " images");
  }
  if (points.size() > static_cast<size_t>(INT_MAX)) throw Error("NCC probe batch too large");
  if (points.empty()) return {};
  static_assert(sizeof(Eigen::Vector2f) == 2 * sizeof(float), "uploaded as float2");
  ClBuffer point_buffer(context_, points.size() * sizeof(Eigen::Vector2f), CL_MEM_READ_ONLY);
  point_buffer.Write(points.data(), points.size() * sizeof(Eigen::Vector2f));
  ClBuffer value_buffer(context_, points.size() * sizeof(float), CL_MEM_WRITE_ONLY);
  probe_kernel_.SetArgs(group_->images, group_->image_table, cl_int{image}, point_buffer,
                        static_cast<cl_int>(points.size()), value_buffer);
  context_.Enqueue(probe_kernel_, NDRange(points.size()),
                   NDRange(static_cast<size_t>(options_.work_group_size)));
  std::vector<float> values(points.size());
  value_buffer.ReadVector(&values);
  return values;
}

std::vector<double> NccScoreReference(const NccGroup& group, const std::vector<NccPatch>& patches,
                                      const std::vector<NccPair>& pairs, int patch_size,
                                      std::vector<double>* border_margin, double sigma_color) {
  NccScorerOptions options;
  options.patch_size = patch_size;
  options.sigma_color = sigma_color;
  const std::string problem = OptionsProblem(options);
  if (!problem.empty()) throw Error("NccScoreReference: expected " + problem);
  group.Validate();
  const int num_images = static_cast<int>(group.images.size());
  ValidateNccBatch(patches, pairs, num_images);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  const int half = patch_size / 2;
  const size_t num_samples = static_cast<size_t>(patch_size) * patch_size;
  // The kernel's sigma is a float literal.
  const double sigma = static_cast<float>(sigma_color);
  std::vector<double> scores(pairs.size(), nan);
  if (border_margin != nullptr) border_margin->assign(pairs.size(), nan);
  std::vector<double> a(num_samples);
  std::vector<double> b(num_samples);
  std::vector<double> weight(num_samples, 1.0);

  for (size_t i = 0; i < pairs.size(); ++i) {
    const NccPatch& patch = patches[pairs[i].patch];
    const int views[2] = {patch.reference, pairs[i].view};
    const NccCamera& ref = group.cameras[patch.reference];
    const Eigen::Vector3d c = Xyz(patch.center);
    const Eigen::Vector3d n = Xyz(patch.normal);
    const double depth = Xyzw(ref.p[2]).dot(c.homogeneous());
    if (!(depth > 0.0)) continue;
    const double step = depth / ref.center.s[3];
    // Same grid axes as the kernel (see ncc_score.cl).
    const Eigen::Vector3d x_proj = Xyz(ref.x_axis) - Xyz(ref.x_axis).dot(n) * n;
    if (!(x_proj.norm() >= kNccMinAxisLength)) continue;
    const Eigen::Vector3d x_dir = x_proj.normalized();
    Eigen::Vector3d y_dir = n.cross(x_dir);
    if (y_dir.dot(Xyz(ref.y_axis)) < 0.0) y_dir = -y_dir;

    bool valid = true;
    double margin = std::numeric_limits<double>::infinity();
    for (int r = 0; r < patch_size && valid; ++r) {
      for (int col = 0; col < patch_size && valid; ++col) {
        const Eigen::Vector3d x = c + ((col - half) * step) * x_dir + ((r - half) * step) * y_dir;
        for (int v = 0; v < 2 && valid; ++v) {
          const NccCamera& camera = group.cameras[views[v]];
          const FloatImageView& image = group.images[views[v]];
          const double w = Xyzw(camera.p[2]).dot(x.homogeneous());
          if (!(w > 0.0)) {
            valid = false;
            break;
          }
          const double u = Xyzw(camera.p[0]).dot(x.homogeneous()) / w;
          const double y = Xyzw(camera.p[1]).dot(x.homogeneous()) / w;
          margin = std::min(margin, BorderDistance(image.layout, u, y));
          const double value = BilinearSampleReference(image, u, y);
          if (std::isnan(value)) valid = false;
          (v == 0 ? a : b)[static_cast<size_t>(r) * patch_size + col] = value;
        }
      }
    }
    if (border_margin != nullptr) (*border_margin)[i] = margin;
    if (!valid) continue;

    if (sigma > 0.0) {
      // Same weights as ncc_weights: the spread of the 3 x 3 samples around
      // the centre, times sigma.
      const size_t mid = num_samples / 2;
      double mean = 0.0, var = 0.0;
      for (int r = -1; r <= 1; ++r)
        for (int q = -1; q <= 1; ++q) mean += a[mid + r * patch_size + q];
      mean /= 9.0;
      for (int r = -1; r <= 1; ++r)
        for (int q = -1; q <= 1; ++q) var += std::pow(a[mid + r * patch_size + q] - mean, 2);
      const double s = sigma * std::sqrt(var / 9.0);
      for (size_t k = 0; k < num_samples; ++k) {
        const double d = a[k] - a[mid];
        weight[k] = s > 0.0 ? std::exp(-0.5 * (d * d) / (s * s)) : 1.0;
      }
    }
    double sum_w = 0.0;
    double mean_a = 0.0;
    double mean_b = 0.0;
    for (size_t k = 0; k < num_samples; ++k) {
      sum_w += weight[k];
      mean_a += weight[k] * a[k];
      mean_b += weight[k] * b[k];
    }
    mean_a /= sum_w;
    mean_b /= sum_w;
    double saa = 0.0;
    double sbb = 0.0;
    double sab = 0.0;
    for (size_t k = 0; k < num_samples; ++k) {
      saa += weight[k] * (a[k] - mean_a) * (a[k] - mean_a);
      sbb += weight[k] * (b[k] - mean_b) * (b[k] - mean_b);
      sab += weight[k] * (a[k] - mean_a) * (b[k] - mean_b);
    }
    const double min_sum = static_cast<double>(kNccMinVariance) * sum_w;
    if (!(saa >= min_sum && sbb >= min_sum)) continue;
    scores[i] = std::clamp(sab / std::sqrt(saa * sbb), -1.0, 1.0);
  }
  return scores;
}

}  // namespace sapmvs
