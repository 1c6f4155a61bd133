#pragma once
// Batched NCC scoring of PMVS patches (kernels/ncc_score.cl), plus its
// double-precision reference. A patch (method.md 3.1) is a small plane: centre
// c, unit normal n, reference image R. Its μ×μ sample grid lies on the plane
// at the spacing of one reference pixel at c (depth / f), along the reference
// camera's x and y axes projected onto the plane; each sample is projected into
// R and into a view, sampled bilinearly (bilinear_sampler.h's border policy),
// and the score is the NCC of the two sample vectors. NaN means "no score":
// a sample outside either image or not in front of its camera, a plane that
// contains the reference x axis, or a sample vector with per-sample variance
// below kNccMinVariance.
//
// Everything is in the block's local frame (Camera::Translated(origin)) and in
// float32 on the device, so local coordinates keep their precision.

#include <CL/cl.h>

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <vector>

#include "bilinear_sampler.h"
#include "cl_runtime.h"
#include "sapmvs/camera.h"
#include "sapmvs/kernel_limits.h"

namespace sapmvs {

// ---------------------------------------------------------------------------
// Kernel argument layouts. Built from cl_float4 / cl_int only, so host and
// OpenCL C agree on size and alignment by construction; the asserts below
// guard the offsets the kernel's typedefs rely on.

// One image's camera, local frame. The projection matrix gives pixels and the
// depth (its third row is that of K [R | t]); the axes and focal length build
// the patch grid.
struct NccCamera {
  cl_float4 p[3];    // Rows of the 3x4 projection matrix K [R | t].
  cl_float4 x_axis;  // Camera x axis in the world frame (row 0 of R_wc); w = 0.
  cl_float4 y_axis;  // Camera y axis in the world frame (row 1 of R_wc); w = 0.
  cl_float4 center;  // xyz: projection centre; w: mean focal length in pixels.
};
static_assert(sizeof(NccCamera) == 96, "NccCamera must match the kernel's 6 x float4");
static_assert(alignof(NccCamera) == 16, "NccCamera must be float4-aligned");
static_assert(offsetof(NccCamera, x_axis) == 48 && offsetof(NccCamera, center) == 80,
              "NccCamera field offsets must match kernels/ncc_score.cl");

// One patch.
struct NccPatch {
  cl_float4 center;  // xyz: centre c, local frame; w ignored.
  cl_float4 normal;  // xyz: unit normal n; w ignored.
  cl_int reference;  // Index of the reference image R(p) in the group.
  cl_int reserved[3] = {0, 0, 0};
};
static_assert(sizeof(NccPatch) == 48, "NccPatch must match the kernel's struct");
static_assert(alignof(NccPatch) == 16, "NccPatch must be float4-aligned");
static_assert(offsetof(NccPatch, reference) == 32, "NccPatch::reference must follow 2 x float4");

// One (patch, view) pair: scores[i] compares patch `patch` in its reference
// image with image `view`. view == reference is allowed (the NCC is then 1
// wherever it is defined).
struct NccPair {
  cl_int patch = 0;
  cl_int view = 0;
};
static_assert(sizeof(NccPair) == sizeof(cl_int2), "NccPair is uploaded as int2");

// The kernel camera of `local_camera` (already Translated to the local
// origin). Throws Error naming `what` for a camera with distortion.
NccCamera MakeNccCamera(const Camera& local_camera, const char* what = "camera");
NccPatch MakeNccPatch(const Eigen::Vector3d& center, const Eigen::Vector3d& normal, int reference);

// The build options of every program that includes ncc.cl (ncc_score.cl,
// patch_refine.cl and roofline_probe.cl): the NCC's variance floor, the
// sample weights, the patch side and the work-group size, so that the three
// score alike.
BuildOptions NccBuildOptions(int patch_size, int work_group_size, double sigma_color);

// ---------------------------------------------------------------------------

struct NccScorerOptions {
  // μ: samples per side of the patch grid, passed as -D PATCH_SIZE. Odd, 3 to
  // kMaxPatchSize.
  int patch_size = kDefaultPatchSize;
  // Work-items per work-group, passed as -D WORK_GROUP_SIZE. Must be >= 1;
  // the device limits are checked at launch.
  int work_group_size = kDefaultWorkGroupSize;
  // Sample weights, passed as -D NCC_SIGMA_COLOR: > 0 weights each sample by
  // exp(-d^2 / 2 s^2), d its difference from the centre sample of the
  // reference window and s = sigma_color standard deviations of the 3 x 3
  // reference samples around the centre (the texture of the centre's
  // surface), so that a window straddling two surfaces scores the one under
  // its centre; 0 = plain NCC (PMVS). Finite, >= 0.
  double sigma_color = 0.0;

  // Logs the first failing condition to stderr and returns false.
  bool Check() const;
};

// A group's images and cameras as the kernel and the reference see them.
// Images are not owned.
struct NccGroup {
  std::vector<FloatImageView> images;
  std::vector<NccCamera> cameras;  // cameras[i] belongs to images[i].

  // Throws Error naming the image at fault: a bad layout, no data, a count
  // mismatch, a non-finite camera or a focal length <= 0.
  void Validate() const;
};

// A group resident on the device: every image packed into one buffer (one
// kernel argument however many images) with an int4 (offset in elements,
// width, height, row pitch) table, and the cameras. The scorer and the
// refiner each keep one for the group they work on.
struct NccDeviceGroup {
  ClBuffer images;
  ClBuffer image_table;
  ClBuffer cameras;
  int num_images = 0;
};

// Validates `group` and uploads it; throws before touching the device when the
// group is invalid or its pixels exceed the kernels' int offsets.
NccDeviceGroup UploadNccGroup(ClContext& context, const NccGroup& group);

class NccScorer {
 public:
  // Builds the kernel (or takes it from the context's program cache). Throws
  // Error if !options.Check(). `context` must outlive the scorer.
  explicit NccScorer(ClContext& context, const NccScorerOptions& options = NccScorerOptions());

  // Validates and uploads the group; its images then stay on the device until
  // the next SetGroup. Blocking.
  void SetGroup(const NccGroup& group);
  // Uses a group already on the device, shared with other scorers and
  // refiners of the same context (one upload, however many patch sizes).
  void UseGroup(std::shared_ptr<const NccDeviceGroup> group);
  int num_images() const { return group_ ? group_->num_images : 0; }

  // scores[i] = NCC of pairs[i] (see NccPair), or NaN. Validates every index
  // and every patch (finite, unit normal within 1e-3) before enqueueing and
  // throws Error naming the first bad pair or patch. Blocking. If `event` is
  // given it receives the kernel's event (for profiling).
  std::vector<float> Score(const std::vector<NccPatch>& patches, const std::vector<NccPair>& pairs,
                           ClEvent* event = nullptr);

  // values[k] = image `image` of the uploaded group at points[k], through
  // ncc.cl's sample_image (bilinear_at over the packed image table).
  std::vector<float> ProbeSamples(int image, const std::vector<Eigen::Vector2f>& points);

  const NccScorerOptions& options() const { return options_; }

 private:
  ClContext& context_;
  NccScorerOptions options_;
  ClKernel score_kernel_;
  ClKernel probe_kernel_;
  std::shared_ptr<const NccDeviceGroup> group_;
};

// Throws Error naming the first pair or patch the kernel must not see.
void ValidateNccBatch(const std::vector<NccPatch>& patches, const std::vector<NccPair>& pairs,
                      int num_images);

// The kernel's twin in double (from the same float inputs), with the same
// geometry and NaN rules. `border_margin`, if given, receives per pair the
// smallest distance in pixels from any sample position to the edge of its
// image's valid region (negative outside): where it is within float32 rounding
// of 0 the kernel may legitimately decide the other way. `sigma_color`: as
// NccScorerOptions::sigma_color.
std::vector<double> NccScoreReference(const NccGroup& group, const std::vector<NccPatch>& patches,
                                      const std::vector<NccPair>& pairs, int patch_size,
                                      std::vector<double>* border_margin = nullptr,
                                      double sigma_color = 0.0);

}  // namespace sapmvs
