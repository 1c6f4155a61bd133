#include "patch_refiner.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <climits>
#include <cmath>
#include <iostream>
#include <limits>
#include <string>

#include "sapmvs/error.h"

namespace sapmvs {
namespace {

constexpr char kKernelFile[] = "patch_refine.cl";
constexpr char kKernel[] = "patch_refine";
constexpr double kPi = 3.14159265358979323846;

// The first failing condition, or "" when the options are usable.
std::string OptionsProblem(const PatchRefinerOptions& o) {
  if (o.patch_size < 3 || o.patch_size > kMaxPatchSize || o.patch_size % 2 != 1) {
    return "patch_size odd, 3 to " + std::to_string(kMaxPatchSize) +
           " (patch_size = " + std::to_string(o.patch_size) + ")";
  }
  if (o.work_group_size < 1) {
    return "work_group_size >= 1 (work_group_size = " + std::to_string(o.work_group_size) + ")";
  }
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

Eigen::Vector3d Xyz(const cl_float4& v) { return {v.s[0], v.s[1], v.s[2]}; }

double Radians(double degrees) { return degrees * kPi / 180.0; }

// The reference's patch frame and start parameters (see patch_refiner.h).
struct Frame {
  Eigen::Vector3d origin, ray, e_x, e_y, e_z;
  double t0 = 0.0;
  double footprint = 0.0;

  Eigen::Vector3d Normal(double yaw, double pitch) const {
    return std::cos(pitch) * std::sin(yaw) * e_x + std::sin(pitch) * e_y +
           std::cos(pitch) * std::cos(yaw) * e_z;
  }
};

Frame MakeFrame(const NccCamera& ref, const NccPatch& patch) {
  Frame f;
  f.origin = Xyz(ref.center);
  const Eigen::Vector3d c0 = Xyz(patch.center);
  f.t0 = (c0 - f.origin).norm();
  f.ray = (c0 - f.origin) / f.t0;
  f.e_z = -f.ray;
  const Eigen::Vector3d x_axis = Xyz(ref.x_axis);
  f.e_x = (x_axis - x_axis.dot(f.e_z) * f.e_z).normalized();
  f.e_y = f.e_z.cross(f.e_x);
  const Eigen::Vector4d p2(ref.p[2].s[0], ref.p[2].s[1], ref.p[2].s[2], ref.p[2].s[3]);
  f.footprint = p2.dot(c0.homogeneous()) / ref.center.s[3];
  return f;
}

}  // namespace

bool PatchRefinerOptions::Check() const {
  const std::string problem = OptionsProblem(*this);
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

PatchRefiner::PatchRefiner(ClContext& context, const PatchRefinerOptions& options)
    : context_(context), options_(options) {
  const std::string problem = OptionsProblem(options);
  if (!problem.empty()) throw Error("PatchRefinerOptions: expected " + problem);
  BuildOptions defines =
      NccBuildOptions(options.patch_size, options.work_group_size, options.sigma_color);
  defines.Define("MAX_VIEWS", kMaxViews);
  kernel_ = context_.Program(kKernelFile, defines).Kernel(kKernel);
}

void PatchRefiner::SetGroup(const NccGroup& group) {
  group_ = std::make_shared<const NccDeviceGroup>(UploadNccGroup(context_, group));
  host_cameras_ = group.cameras;
}

void PatchRefiner::UseGroup(std::shared_ptr<const NccDeviceGroup> group,
                            std::vector<NccCamera> cameras) {
  if (!group || group->num_images == 0 || static_cast<int>(cameras.size()) != group->num_images) {
    throw Error("PatchRefiner::UseGroup: no images, or cameras do not match the group");
  }
  group_ = std::move(group);
  host_cameras_ = std::move(cameras);
}

std::vector<RefinedPatch> PatchRefiner::Refine(const std::vector<NccPatch>& patches,
                                               const std::vector<std::vector<int>>& views,
                                               ClEvent* event) {
  if (num_images() == 0) throw Error("PatchRefiner::Refine called before SetGroup");
  ValidatePatchRefineBatch(patches, views, host_cameras_);
  if (patches.empty()) return {};

  std::vector<cl_int> offsets(patches.size() + 1, 0);
  std::vector<cl_int> indices;
  for (size_t i = 0; i < views.size(); ++i) {
    indices.insert(indices.end(), views[i].begin(), views[i].end());
    offsets[i + 1] = static_cast<cl_int>(indices.size());
  }
  ClBuffer patch_buffer(context_, patches.size() * sizeof(NccPatch), CL_MEM_READ_ONLY);
  patch_buffer.WriteVector(patches);
  ClBuffer offset_buffer(context_, offsets.size() * sizeof(cl_int), CL_MEM_READ_ONLY);
  offset_buffer.WriteVector(offsets);
  ClBuffer index_buffer(context_, indices.size() * sizeof(cl_int), CL_MEM_READ_ONLY);
  index_buffer.WriteVector(indices);
  ClBuffer result_buffer(context_, patches.size() * sizeof(RefinedPatchOut), CL_MEM_WRITE_ONLY);
  ClBuffer score_buffer(context_, indices.size() * sizeof(float), CL_MEM_WRITE_ONLY);

  kernel_.SetArgs(group_->images, group_->image_table, group_->cameras, cl_int{group_->num_images},
                  patch_buffer, static_cast<cl_int>(patches.size()), offset_buffer, index_buffer,
                  cl_int{options_.iterations}, cl_int{options_.max_halvings},
                  static_cast<cl_float>(options_.depth_step),
                  static_cast<cl_float>(Radians(options_.angle_step_deg)),
                  static_cast<cl_float>(Radians(options_.max_angle_deg)), result_buffer,
                  score_buffer);
  ClEvent launched = context_.Enqueue(kernel_, NDRange(patches.size()),
                                      NDRange(static_cast<size_t>(options_.work_group_size)));
  std::vector<RefinedPatchOut> out(patches.size());
  result_buffer.ReadVector(&out);
  std::vector<float> scores(indices.size());
  score_buffer.ReadVector(&scores);
  if (event != nullptr) *event = std::move(launched);

  std::vector<RefinedPatch> refined(patches.size());
  for (size_t i = 0; i < patches.size(); ++i) {
    RefinedPatch& r = refined[i];
    r.patch = patches[i];
    for (int k = 0; k < 3; ++k) {
      r.patch.center.s[k] = out[i].center.s[k];
      r.patch.normal.s[k] = out[i].normal.s[k];
    }
    r.patch.center.s[3] = 0.0f;
    r.patch.normal.s[3] = 0.0f;
    r.score = out[i].center.s[3];
    r.view_scores.assign(scores.begin() + offsets[i], scores.begin() + offsets[i + 1]);
    r.depth_offset = out[i].params.s[0];
    r.yaw = out[i].params.s[1];
    r.pitch = out[i].params.s[2];
    r.moves = static_cast<int>(out[i].params.s[3]);
  }
  return refined;
}

std::vector<RefinedPatchReference> PatchRefineReference(const NccGroup& group,
                                                        const std::vector<NccPatch>& patches,
                                                        const std::vector<std::vector<int>>& views,
                                                        const PatchRefinerOptions& options) {
  const std::string problem = OptionsProblem(options);
  if (!problem.empty()) throw Error("PatchRefineReference: expected " + problem);
  group.Validate();
  ValidatePatchRefineBatch(patches, views, group.cameras);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  // Single-precision step values, as the kernel receives them.
  const double angle_step = static_cast<float>(Radians(options.angle_step_deg));
  const double max_angle = static_cast<float>(Radians(options.max_angle_deg));
  const double depth_step = static_cast<float>(options.depth_step);

  std::vector<RefinedPatchReference> results(patches.size());
  for (size_t i = 0; i < patches.size(); ++i) {
    const NccPatch& patch = patches[i];
    const Frame f = MakeFrame(group.cameras[patch.reference], patch);
    const std::vector<int>& list = views[i];
    std::vector<NccPair> pairs;
    for (int v : list) pairs.push_back({0, v});
    // Mean NCC at (t, yaw, pitch); NaN when invalid.
    auto evaluate = [&](const double q[3], std::vector<double>* nccs) {
      nccs->assign(list.size(), nan);
      if (!(std::abs(q[1]) <= max_angle && std::abs(q[2]) <= max_angle)) return nan;
      const Eigen::Vector3d n = f.Normal(q[1], q[2]);
      *nccs = NccScoreReference(group, {MakeNccPatch(f.origin + q[0] * f.ray, n, patch.reference)},
                                pairs, options.patch_size, nullptr, options.sigma_color);
      double sum = 0.0;
      for (double s : *nccs) {
        if (std::isnan(s)) return nan;
        sum += s;
      }
      return sum / static_cast<double>(list.size());
    };
    auto improves = [](double s, double best) {
      return !std::isnan(s) && (std::isnan(best) || s > best);
    };

    const Eigen::Vector3d n0 = Xyz(patch.normal);
    double p[3] = {f.t0, std::atan2(n0.dot(f.e_x), n0.dot(f.e_z)),
                   std::asin(std::clamp(n0.dot(f.e_y), -1.0, 1.0))};
    double step[3] = {depth_step * f.footprint, angle_step, angle_step};
    RefinedPatchReference& r = results[i];
    double score = evaluate(p, &r.view_scores);
    double margin = inf;
    std::vector<double> trial;
    int halvings = 0;
    for (int it = 0; it < options.iterations && halvings < options.max_halvings; ++it) {
      double best = score;
      int best_k = -1;
      std::vector<double> valid_scores;
      if (!std::isnan(score)) valid_scores.push_back(score);
      std::vector<double> best_nccs;
      for (int k = 0; k < 6; ++k) {
        double q[3] = {p[0], p[1], p[2]};
        q[k / 2] += (k % 2 == 0) ? step[k / 2] : -step[k / 2];
        const double s = evaluate(q, &trial);
        if (!std::isnan(s)) valid_scores.push_back(s);
        if (improves(s, best)) {
          best = s;
          best_k = k;
          best_nccs = trial;
        }
      }
      // Gap between the winner and the runner-up among the valid scores.
      std::sort(valid_scores.begin(), valid_scores.end());
      if (valid_scores.size() >= 2) {
        margin = std::min(margin, valid_scores.back() - valid_scores[valid_scores.size() - 2]);
      }
      if (best_k >= 0) {
        p[best_k / 2] += (best_k % 2 == 0) ? step[best_k / 2] : -step[best_k / 2];
        score = best;
        r.view_scores = best_nccs;
        ++r.moves;
      } else {
        for (double& s : step) s *= 0.5;
        ++halvings;
      }
    }
    r.center = f.origin + p[0] * f.ray;
    r.normal = f.Normal(p[1], p[2]);
    r.score = score;
    r.depth_offset = (p[0] - f.t0) / f.footprint;
    r.yaw = p[1];
    r.pitch = p[2];
    r.decision_margin = margin;
  }
  return results;
}

}  // namespace sapmvs
