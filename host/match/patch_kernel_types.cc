#include "match/patch_kernel_types.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <iostream>
#include <string>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// How far from unit length a patch normal may be; the kernels do not
// renormalise, so a sloppy normal would silently shear the grid.
constexpr double kUnitNormalTolerance = 1e-3;

// The checks NccScorerOptions and PatchRefinerOptions share: "" or what was
// expected.
std::string SampleStepProblem(double sample_step) {
  if (sample_step >= 1.0 && sample_step <= kMaxSampleStep) return "";
  return "sample_step 1 to " + std::to_string(kMaxSampleStep) +
         " (sample_step = " + std::to_string(sample_step) + ")";
}

std::string WorkGroupSizeProblem(int work_group_size) {
  if (work_group_size >= 1) return "";
  return "work_group_size >= 1 (work_group_size = " + std::to_string(work_group_size) + ")";
}

Float4 ToFloat4(double x, double y, double z, double w) {
  Float4 v;
  v.s[0] = static_cast<float>(x);
  v.s[1] = static_cast<float>(y);
  v.s[2] = static_cast<float>(z);
  v.s[3] = static_cast<float>(w);
  return v;
}

bool AllFinite(const Float4& v, int n) {
  for (int k = 0; k < n; ++k) {
    if (!std::isfinite(v.s[k])) return false;
  }
  return true;
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
    camera.p[row] = ToFloat4(p(row, 0), p(row, 1), p(row, 2), p(row, 3));
  camera.x_axis = ToFloat4(r(0, 0), r(0, 1), r(0, 2), 0.0);
  camera.y_axis = ToFloat4(r(1, 0), r(1, 1), r(1, 2), 0.0);
  camera.center = ToFloat4(c.x(), c.y(), c.z(), local_camera.intrinsics().MeanFocal());
  return camera;
}

NccPatch MakeNccPatch(const Eigen::Vector3d& center, const Eigen::Vector3d& normal, int reference) {
  NccPatch patch;
  patch.center = ToFloat4(center.x(), center.y(), center.z(), 0.0);
  patch.normal = ToFloat4(normal.x(), normal.y(), normal.z(), 0.0);
  patch.reference = reference;
  return patch;
}

std::string NccScorerOptions::Problem() const {
  const NccScorerOptions& o = *this;
  const std::string got = " (patch_size = " + std::to_string(o.patch_size) + ")";
  if (o.patch_size < 3) return "patch_size >= 3" + got;
  if (o.patch_size > kMaxPatchSize) {
    return "patch_size <= kMaxPatchSize = " + std::to_string(kMaxPatchSize) + got;
  }
  if (o.patch_size % 2 != 1) return "patch_size is odd" + got;
  if (std::string p = SampleStepProblem(o.sample_step); !p.empty()) return p;
  if (std::string p = WorkGroupSizeProblem(o.work_group_size); !p.empty()) return p;
  if (!(std::isfinite(o.sigma_color) && o.sigma_color >= 0.0)) {
    return "sigma_color finite and >= 0 (sigma_color = " + std::to_string(o.sigma_color) + ")";
  }
  return "";
}

bool NccScorerOptions::Check() const {
  const std::string problem = Problem();
  if (problem.empty()) return true;
  std::cerr << "NccScorerOptions: check failed: " << problem << "\n";
  return false;
}

std::string PatchRefinerOptions::Problem() const {
  const PatchRefinerOptions& o = *this;
  if (o.patch_size < 3 || o.patch_size > kMaxPatchSize || o.patch_size % 2 != 1) {
    return "patch_size odd, 3 to " + std::to_string(kMaxPatchSize) +
           " (patch_size = " + std::to_string(o.patch_size) + ")";
  }
  if (std::string p = SampleStepProblem(o.sample_step); !p.empty()) return p;
  if (std::string p = WorkGroupSizeProblem(o.work_group_size); !p.empty()) return p;
  if (o.iterations < 0 || o.iterations > kMaxRefineIterations) {
    return "iterations 0 to " + std::to_string(kMaxRefineIterations) +
           " (iterations = " + std::to_string(o.iterations) + ")";
  }
  if (o.max_halvings < 1) {
    return "max_halvings >= 1 (max_halvings = " + std::to_string(o.max_halvings) + ")";
  }
  if (!(std::isfinite(o.depth_step) && o.depth_step > 0.0)) {
    return "depth_step finite and > 0 (depth_step = " + std::to_string(o.depth_step) + ")";
  }
  if (!(o.angle_step_deg > 0.0 && o.angle_step_deg <= 45.0)) {
    return "angle_step_deg in (0, 45] (angle_step_deg = " + std::to_string(o.angle_step_deg) + ")";
  }
  if (!(std::isfinite(o.sigma_color) && o.sigma_color >= 0.0)) {
    return "sigma_color finite and >= 0 (sigma_color = " + std::to_string(o.sigma_color) + ")";
  }
  if (!(o.max_angle_deg > 0.0 && o.max_angle_deg <= 89.0)) {
    return "max_angle_deg in (0, 89] (max_angle_deg = " + std::to_string(o.max_angle_deg) + ")";
  }
  return "";
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
    for (const Float4& row : camera.p) finite = finite && AllFinite(row, 4);
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

bool PatchRefinerOptions::Check() const {
  const std::string problem = Problem();
  if (problem.empty()) return true;
  std::cerr << "PatchRefinerOptions: check failed: " << problem << "\n";
  return false;
}

void ValidatePatchRefineBatch(const std::vector<NccPatch>& patches,
                              const std::vector<std::vector<int>>& views,
                              const std::vector<NccCamera>& cameras) {
  const int num_images = static_cast<int>(cameras.size());
  ValidateNccBatch(patches, {}, num_images);
  if (views.size() != patches.size()) {
    throw Error("patch refinement: " + std::to_string(patches.size()) + " patches but " +
                std::to_string(views.size()) + " view lists");
  }
  size_t total = 0;
  for (size_t i = 0; i < patches.size(); ++i) {
    const std::string name = "patch refinement patch " + std::to_string(i);
    const std::vector<int>& list = views[i];
    if (list.empty() || list.size() > static_cast<size_t>(kMaxViews)) {
      throw Error(name + " has " + std::to_string(list.size()) + " views, expected 1 to " +
                  std::to_string(kMaxViews));
    }
    total += list.size();
    for (size_t k = 0; k < list.size(); ++k) {
      if (list[k] < 0 || list[k] >= num_images) {
        throw Error(name + ": view " + std::to_string(list[k]) + " is not in the group of " +
                    std::to_string(num_images) + " images");
      }
      if (list[k] == patches[i].reference) {
        throw Error(name + ": view " + std::to_string(list[k]) + " is its reference image");
      }
      if (std::find(list.begin(), list.begin() + static_cast<long>(k), list[k]) !=
          list.begin() + static_cast<long>(k)) {
        throw Error(name + ": view " + std::to_string(list[k]) + " is listed twice");
      }
    }
    const Eigen::Vector3d to_camera =
        Xyz(cameras[patches[i].reference].center) - Xyz(patches[i].center);
    if (!(Xyz(patches[i].normal).dot(to_camera) > 0.0)) {
      throw Error(name + ": normal does not face its reference camera");
    }
  }
  if (total > static_cast<size_t>(INT_MAX)) throw Error("patch refinement batch too large");
}

}  // namespace sapmvs
