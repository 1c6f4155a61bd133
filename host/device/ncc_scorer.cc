#include "device/ncc_scorer.h"

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

// patch_kernel_types.h builds the kernel structs without OpenCL headers.
static_assert(sizeof(Float4) == sizeof(cl_float4) && alignof(Float4) == alignof(cl_float4),
              "Float4 must be laid out as cl_float4");
static_assert(sizeof(NccPair) == sizeof(cl_int2), "NccPair is uploaded as int2");

}  // namespace

BuildOptions NccBuildOptions(int patch_size, int work_group_size, double sigma_color,
                             double sample_step) {
  BuildOptions defines;
  defines.Define("NCC_MIN_VARIANCE", kNccMinVariance)
      .Define("NCC_SIGMA_COLOR", static_cast<float>(sigma_color))
      .Define("NCC_WEIGHT_MIN_SPREAD", kNccWeightMinSpread)
      .Define("PATCH_SIZE", patch_size)
      .Define("SAMPLE_STEP", static_cast<float>(sample_step))
      .Define("WORK_GROUP_SIZE", work_group_size);
  return defines;
}

NccScorer::NccScorer(ClContext& context, const NccScorerOptions& options)
    : context_(context), options_(options) {
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("NccScorerOptions: expected " + problem);
  const ClProgram& program =
      context_.Program(kKernelFile, NccBuildOptions(options.patch_size, options.work_group_size,
                                                    options.sigma_color, options.sample_step));
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
  // In place: the block holds the images at the table's offsets, and the
  // device reads host memory as its own. Its alignment is left to the
  // implementation, which copies where it must.
  bool in_place = group.pixels != nullptr && context.device().host_unified_memory;
  for (size_t i = 0; in_place && i < group.images.size(); ++i) {
    in_place = group.images[i].data == group.pixels.get() + table[i].s[0];
  }
  ClBuffer images;
  if (in_place) {
    images = ClBuffer::ReadOnlyInPlace(context, group.pixels.get(), total * sizeof(float));
  } else {
    images = ClBuffer(context, total * sizeof(float), CL_MEM_READ_ONLY);
    for (size_t i = 0; i < group.images.size(); ++i) {
      images.Write(group.images[i].data, group.images[i].layout.RequiredElements() * sizeof(float),
                   static_cast<size_t>(table[i].s[0]) * sizeof(float));
    }
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
  if (in_place) out.pixels = group.pixels;
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
  // Runs of consecutive pairs of one patch, one work-item each, which samples
  // the patch's reference window once for the run: callers list a patch's
  // views together.
  std::vector<cl_int> run_offsets = {0};
  for (size_t i = 1; i < pairs.size(); ++i) {
    if (pairs[i].patch != pairs[i - 1].patch) run_offsets.push_back(static_cast<cl_int>(i));
  }
  run_offsets.push_back(static_cast<cl_int>(pairs.size()));
  const size_t num_runs = run_offsets.size() - 1;
  ClBuffer run_buffer(context_, run_offsets.size() * sizeof(cl_int), CL_MEM_READ_ONLY);
  run_buffer.WriteVector(run_offsets);
  ClBuffer score_buffer(context_, pairs.size() * sizeof(float), CL_MEM_WRITE_ONLY);

  ClEvent launched = context_.Launch(
      score_kernel_, NDRange(num_runs), NDRange(static_cast<size_t>(options_.work_group_size)),
      group_->images, group_->image_table, group_->cameras, cl_int{group_->num_images},
      patch_buffer, static_cast<cl_int>(patches.size()), pair_buffer, run_buffer,
      static_cast<cl_int>(num_runs), score_buffer);
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
  context_.Launch(probe_kernel_, NDRange(points.size()),
                  NDRange(static_cast<size_t>(options_.work_group_size)), group_->images,
                  group_->image_table, cl_int{image}, point_buffer,
                  static_cast<cl_int>(points.size()), value_buffer);
  std::vector<float> values(points.size());
  value_buffer.ReadVector(&values);
  return values;
}

}  // namespace sapmvs
