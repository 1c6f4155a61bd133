#pragma once
// What the patch kernels take and give (method.md 3.1): a group's images and
// cameras, patches, (patch, view) pairs, refined patches and the options of a
// score or a refinement, with the checks every backend runs before it works.
// The structs are the kernels' argument layouts, so the OpenCL backend
// uploads them as they are; they are built from plain floats and ints so the
// matcher and the CPU reference can use them without any OpenCL header
// (cl_patch_kernels.cc asserts that Float4 is laid out as cl_float4).
//
// A patch is a small plane: centre c, unit normal n, reference image R. Its
// μ×μ sample grid lies on the plane at the spacing of one reference pixel at
// c (depth / f), along the reference camera's x and y axes projected onto the
// plane; each sample is projected into R and into a view, sampled bilinearly
// (float_image.h's border policy), and the score is the NCC of the two
// sample vectors. NaN means "no score": a sample outside either image or not
// in front of its camera, a plane that contains the reference x axis, or a
// sample vector with per-sample variance below kNccMinVariance. Everything
// is in the block's local frame (Camera::Translated(origin)) and in float32
// on a device, so local coordinates keep their precision.

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "match/float_image.h"
#include "sapmvs/block/camera.h"
#include "sapmvs/util/kernel_limits.h"

namespace sapmvs {

// OpenCL C's float4: four floats, 16-byte aligned; s[] as in cl_float4.
struct alignas(16) Float4 {
  float s[4] = {0.0f, 0.0f, 0.0f, 0.0f};
};
static_assert(sizeof(Float4) == 16, "Float4 must be four packed floats");

// One image's camera, local frame. The projection matrix gives pixels and the
// depth (its third row is that of K [R | t]); the axes and focal length build
// the patch grid.
struct NccCamera {
  Float4 p[3];    // Rows of the 3x4 projection matrix K [R | t].
  Float4 x_axis;  // Camera x axis in the world frame (row 0 of R_wc); w = 0.
  Float4 y_axis;  // Camera y axis in the world frame (row 1 of R_wc); w = 0.
  Float4 center;  // xyz: projection centre; w: mean focal length in pixels.
};
static_assert(sizeof(NccCamera) == 96, "NccCamera must match the kernel's 6 x float4");
static_assert(alignof(NccCamera) == 16, "NccCamera must be float4-aligned");
static_assert(offsetof(NccCamera, x_axis) == 48 && offsetof(NccCamera, center) == 80,
              "NccCamera field offsets must match kernels/ncc_score.cl");

// One patch.
struct NccPatch {
  Float4 center;          // xyz: centre c, local frame; w ignored.
  Float4 normal;          // xyz: unit normal n; w ignored.
  int32_t reference = 0;  // Index of the reference image R(p) in the group.
  // The refinement's search directions: 2 = depth only (the normal kept),
  // anything else depth and both angles. The scorer ignores it.
  int32_t directions = 6;
  int32_t reserved[2] = {0, 0};
};
static_assert(sizeof(NccPatch) == 48, "NccPatch must match the kernel's struct");
static_assert(alignof(NccPatch) == 16, "NccPatch must be float4-aligned");
static_assert(offsetof(NccPatch, reference) == 32, "NccPatch::reference must follow 2 x float4");

// The number of search directions NccPatch::directions stands for, as
// kernels/patch_search.cl's search_directions reads it.
inline int SearchDirections(const NccPatch& patch) { return patch.directions == 2 ? 2 : 6; }

// One (patch, view) pair: scores[i] compares patch `patch` in its reference
// image with image `view`. view == reference is allowed (the NCC is then 1
// wherever it is defined).
struct NccPair {
  int32_t patch = 0;
  int32_t view = 0;
};
static_assert(sizeof(NccPair) == 8, "NccPair is uploaded as int2");

// One refined patch as the refinement kernel writes it (48 bytes, 3 x float4).
struct RefinedPatchOut {
  Float4 center;  // xyz: refined centre; w: mean NCC over the views (NaN: none valid).
  Float4 normal;  // xyz: refined unit normal; w: candidates scored, the start included.
  Float4 params;  // x: t - t0 in footprints of the start; y: yaw; z: pitch (radians);
                  // w: number of accepted moves.
};
static_assert(sizeof(RefinedPatchOut) == 48, "RefinedPatchOut must match the kernel's struct");

// The kernel camera of `local_camera` (already Translated to the local
// origin). Throws Error naming `what` for a camera with distortion.
NccCamera MakeNccCamera(const Camera& local_camera, const char* what = "camera");
NccPatch MakeNccPatch(const Eigen::Vector3d& center, const Eigen::Vector3d& normal, int reference);

// A group's images and cameras as the kernels and the reference see them.
// Images are not owned.
struct NccGroup {
  std::vector<FloatImageView> images;
  std::vector<NccCamera> cameras;  // cameras[i] belongs to images[i].
  // Optional: one allocation that holds every image, one after the other
  // with their rows packed, as the kernels' single image buffer lays them
  // out (LoadMatchGroup's group). A device that shares the host's memory
  // (PoCL's CPU device) then reads the images where they are instead of a
  // copy of them all, and keeps this block alive as long as it does.
  std::shared_ptr<const float> pixels;

  // Throws Error naming the image at fault: a bad layout, no data, a count
  // mismatch, a non-finite camera or a focal length <= 0.
  void Validate() const;
};

struct NccScorerOptions {
  // μ: samples per side of the patch grid, passed as -D PATCH_SIZE. Odd, 3 to
  // kMaxPatchSize.
  int patch_size = kDefaultPatchSize;
  // Spacing of the samples, in reference pixels (the footprints of one
  // reference pixel on the patch), passed as -D SAMPLE_STEP: the grid spans
  // (patch_size - 1) * sample_step pixels. 1 samples every pixel (PMVS);
  // larger steps let a large window be scored from fewer samples. Finite,
  // 1 to kMaxSampleStep.
  double sample_step = 1.0;
  // Work-items per work-group, passed as -D WORK_GROUP_SIZE. Must be >= 1;
  // the device limits are checked at launch (the CPU reference ignores it).
  int work_group_size = kDefaultWorkGroupSize;
  // Sample weights, passed as -D NCC_SIGMA_COLOR: > 0 weights each sample by
  // exp(-d^2 / 2 s^2), d its difference from the centre sample of the
  // reference window and s = sigma_color standard deviations of the 3 x 3
  // reference samples around the centre (the texture of the centre's
  // surface; at least kNccWeightMinSpread), so that a window straddling two
  // surfaces scores the one under its centre; 0 = plain NCC (PMVS). Finite,
  // >= 0.
  double sigma_color = 0.0;

  // Logs the first failing condition to stderr and returns false.
  bool Check() const;
  // The first failing condition as "what was expected (name = value)", or "".
  std::string Problem() const;
};

// How an OpenCL device runs the refinement's search: each patch in one
// work-item (kernels/patch_refine.cl), or in one work-group whose work-items
// share its window's samples (patch_refine_group.cl). kAuto takes a work-group
// on GPUs and other non-CPU devices, a work-item on CPUs. Both give the same
// search; their scores differ in the last bits (the order of the sums).
enum class RefineLayout { kAuto, kPatchPerItem, kPatchPerGroup };

// The refinement's search (patch_refiner.h describes it).
struct PatchRefinerOptions {
  // μ: samples per side of the patch grid (-D PATCH_SIZE). Odd, 3 to kMaxPatchSize.
  int patch_size = kDefaultPatchSize;
  // Spacing of the samples in reference pixels (NccScorerOptions::sample_step).
  double sample_step = 1.0;
  // Work-items per work-group (-D WORK_GROUP_SIZE) where a work-item
  // searches a patch, >= 1 (a work-group per patch has RefineGroupWorkItems;
  // the CPU reference ignores both).
  int work_group_size = kDefaultWorkGroupSize;
  // Work-item or work-group per patch (the CPU reference ignores it).
  RefineLayout layout = RefineLayout::kAuto;
  // Search rounds, each scoring 6 candidates; 0 to kMaxRefineIterations.
  int iterations = kDefaultRefineIterations;
  // Stop after the steps were halved this many times (converged); >= 1.
  int max_halvings = kDefaultRefineHalvings;
  // Initial step of t, in footprints (depth / f of the reference camera at
  // the initial centre); finite and > 0.
  double depth_step = kDefaultRefineDepthStep;
  // Initial step of yaw and pitch, in degrees; finite, > 0 and <= 45.
  double angle_step_deg = kDefaultRefineAngleStepDeg;
  // Largest angle between a candidate's normal and the direction to the
  // reference camera, in degrees; (0, 89].
  double max_angle_deg = kDefaultRefineMaxAngleDeg;
  // Sample weights of the NCC (NccScorerOptions::sigma_color); finite, >= 0
  // (0 = plain NCC).
  double sigma_color = 0.0;

  // Logs the first failing condition to stderr and returns false.
  bool Check() const;
  // The first failing condition as "what was expected (name = value)", or "".
  std::string Problem() const;
};

// One refined patch, host side.
struct RefinedPatch {
  NccPatch patch;                  // Refined centre and normal; same reference.
  float score = 0.0f;              // Mean NCC over the views; NaN if never valid.
  std::vector<float> view_scores;  // NCC per view, in the order given.
  float depth_offset = 0.0f;       // t - t0, in footprints of the start.
  float yaw = 0.0f;                // Radians.
  float pitch = 0.0f;              // Radians.
  int moves = 0;                   // Accepted moves.
  int evaluations = 0;             // Candidates scored, the start included.
};

// Throws Error naming the first pair or patch the kernel must not see: an
// index outside the batch or the group, a non-finite patch, a normal not of
// unit length within 1e-3 (the kernels do not renormalise, so a sloppy normal
// would silently shear the grid).
void ValidateNccBatch(const std::vector<NccPatch>& patches, const std::vector<NccPair>& pairs,
                      int num_images);

// Throws Error unless: the patches pass ValidateNccBatch; views.size() ==
// patches.size(); each list has 1 to kMaxViews distinct views in the group,
// none the patch's reference; each normal faces the reference camera
// (n . (C - c) > 0, which also excludes c == C).
void ValidatePatchRefineBatch(const std::vector<NccPatch>& patches,
                              const std::vector<std::vector<int>>& views,
                              const std::vector<NccCamera>& cameras);

// Helpers shared by the backends and the references.
inline Eigen::Vector3d Xyz(const Float4& v) { return {v.s[0], v.s[1], v.s[2]}; }
inline Eigen::Vector4d Xyzw(const Float4& v) { return {v.s[0], v.s[1], v.s[2], v.s[3]}; }

}  // namespace sapmvs
