// Batched NCC scoring of PMVS patches (method.md 3.1): one work-item per
// patch and its run of (patch, view) pairs. See kernels/README.md for the
// data layout; the structs and NCC primitives are in ncc.cl, their host
// mirrors in host/device/ncc_scorer.h (with static_asserts on their layout),
// and NccScoreReference (host/match/ncc_score_reference.cc) is the
// double-precision twin that must keep exactly the same geometry and NaN
// rules.
//
// All coordinates are local (relative to the block's origin), in float32.
//
// Build options (the host passes all of them; see sapmvs/kernel_limits.h):
//   WORK_GROUP_SIZE   work-items per group; the launch must use exactly this.
//   PATCH_SIZE        μ, samples per side of the patch grid (odd).
//   NCC_MIN_VARIANCE  smallest per-sample variance of a sample vector.
//   NCC_SIGMA_COLOR   > 0 weights the NCC samples (ncc_weights); 0 = plain NCC.
//   SAMPLE_STEP       spacing of the grid's samples, in reference pixels.

#ifndef WORK_GROUP_SIZE
#define WORK_GROUP_SIZE 64
#endif

#include "ncc.cl"

// scores[i] = NCC of patch pairs[i].x between its reference image and image
// pairs[i].y, for i < num_pairs; NaN when any sample is outside either image
// or not in front of its camera, a window ray meets the plane behind the
// reference, the plane is seen too obliquely, or a sample vector is flat.
// One work-item per run of pairs [run_offsets[r], run_offsets[r + 1])
// that share one patch (the host cuts pairs into runs of equal pairs[i].x):
// the patch's reference window is sampled, weighted and centred once for all
// of its views, where one work-item per pair sampled it once per view.
// Out-of-range indices also give NaN (the host rejects them first; the
// guard only keeps a bad device-side batch from reading out of bounds).
__kernel __attribute__((reqd_work_group_size(WORK_GROUP_SIZE, 1, 1))) void ncc_score(
    __global const float* restrict images, __global const int4* restrict image_table,
    __global const NccCamera* restrict cameras, const int num_images,
    __global const NccPatch* restrict patches, const int num_patches,
    __global const int2* restrict pairs, __global const int* restrict run_offsets,
    const int num_runs, __global float* restrict scores) {
  const int run = (int)get_global_id(0);
  if (run >= num_runs) {
    return;
  }
  const int first = run_offsets[run];
  const int end = run_offsets[run + 1];
  for (int i = first; i < end; ++i) {
    scores[i] = NAN;
  }
  const int patch_index = pairs[first].x;
  if (patch_index < 0 || patch_index >= num_patches) {
    return;
  }
  const NccPatch patch = patches[patch_index];
  if (patch.reference < 0 || patch.reference >= num_images) {
    return;
  }
  const NccCamera ref = cameras[patch.reference];
  const float3 c = patch.center.xyz;
  const float3 n = patch.normal.xyz;
  ReferenceWindow win;
  if (!plane_seen(ref, c, n) || !reference_window(ref, c, &win)) {
    return;
  }
  const int half_size = PATCH_SIZE / 2;
  float a[NCC_NUM_SAMPLES];
  for (int r = 0; r < PATCH_SIZE; ++r) {
    for (int col = 0; col < PATCH_SIZE; ++col) {
      const float va = sample_reference(images, image_table, patch.reference, win,
                                        (float)(r - half_size), (float)(col - half_size));
      // One NaN sample (outside or a NaN pixel) voids every pair.
      if (isnan(va)) {
        return;
      }
      a[r * PATCH_SIZE + col] = va;
    }
  }
  float w[NCC_NUM_SAMPLES];
  ncc_weights(a, w);
  float sum_w;
  float saa;
  if (!ncc_centre(a, w, &sum_w, &saa)) {
    return;
  }
  float b[NCC_SAMPLE_BUFFER];
  for (int i = first; i < end; ++i) {
    const int2 pair = pairs[i];
    GridProjection gb;
    if (pair.x != patch_index || pair.y < 0 || pair.y >= num_images ||
        !window_projection(cameras[pair.y], win, c, n, &gb)) {
      continue;
    }
    // One NaN sample (outside, behind, or a NaN pixel) voids the pair.
    if (sample_view(images, image_table, pair.y, gb, b)) {
      scores[i] = ncc_against(a, sum_w, saa, b, w);
    }
  }
}

// values[k] = image `image_index` of the packed buffer at points[k]; exposes
// the copied bilinear_at and the image table to the tests.
__kernel __attribute__((reqd_work_group_size(WORK_GROUP_SIZE, 1, 1))) void ncc_sample_probe(
    __global const float* restrict images, __global const int4* restrict image_table,
    const int image_index, __global const float2* restrict points, const int num_points,
    __global float* restrict values) {
  const int k = (int)get_global_id(0);
  if (k >= num_points) {
    return;
  }
  const float2 p = points[k];
  values[k] = sample_image(images, image_table, image_index, p.x, p.y);
}
