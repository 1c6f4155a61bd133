#include "device/patch_refiner.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <climits>
#include <cmath>
#include <iostream>
#include <limits>
#include <string>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

constexpr char kItemFile[] = "patch_refine.cl";
constexpr char kItemKernel[] = "patch_refine";
constexpr char kGroupFile[] = "patch_refine_group.cl";
constexpr char kGroupKernel[] = "patch_refine_group";
constexpr double kPi = 3.14159265358979323846;

double Radians(double degrees) { return degrees * kPi / 180.0; }

}  // namespace

PatchRefiner::PatchRefiner(ClContext& context, const PatchRefinerOptions& options)
    : context_(context), options_(options) {
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("PatchRefinerOptions: expected " + problem);
  per_group_ = options.layout == RefineLayout::kPatchPerGroup ||
               (options.layout == RefineLayout::kAuto && context.device().type != DeviceType::kCpu);
  local_size_ = per_group_ ? RefineGroupWorkItems(options.patch_size) : options.work_group_size;
  BuildOptions defines =
      NccBuildOptions(options.patch_size, local_size_, options.sigma_color, options.sample_step);
  defines.Define("MAX_VIEWS", kMaxViews);
  kernel_ = context_.Program(per_group_ ? kGroupFile : kItemFile, defines)
                .Kernel(per_group_ ? kGroupKernel : kItemKernel);
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

  const size_t local = static_cast<size_t>(local_size_);
  ClEvent launched = context_.Launch(
      kernel_, NDRange(per_group_ ? patches.size() * local : patches.size()), NDRange(local),
      group_->images, group_->image_table, group_->cameras, cl_int{group_->num_images},
      patch_buffer, static_cast<cl_int>(patches.size()), offset_buffer, index_buffer,
      cl_int{options_.iterations}, cl_int{options_.max_halvings},
      static_cast<cl_float>(options_.depth_step),
      static_cast<cl_float>(Radians(options_.angle_step_deg)),
      static_cast<cl_float>(Radians(options_.max_angle_deg)), result_buffer, score_buffer);
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
    r.evaluations = static_cast<int>(out[i].normal.s[3]);
  }
  return refined;
}

}  // namespace sapmvs
