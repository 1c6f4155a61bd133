// Batched NCC scoring of PMVS patches (method.md 3.1): one work-item per
// (patch, view) pair. See kernels/README.md for the data layout; the structs
// and NCC primitives are in ncc.cl, their host mirrors in host/device/ncc_scorer.h
// (with static_asserts on their layout), and NccScoreReference (host/device/ncc_scorer.cc) is the
// double-precision twin that must keep exactly the same geometry and NaN rules.
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
// or not in front of its camera, the grid is undefined, or a sample vector is
// flat. Out-of-range indices also give NaN (the host rejects them first; the
// guard only keeps a bad device-side batch from reading out of bounds).
__kernel __attribute__((reqd_work_group_size(WORK_GROUP_SIZE, 1, 1))) void ncc_score(
    __global const float* restrict images, __global const int4* restrict image_table,
    __global const NccCamera* restrict cameras, const int num_images,
    __global const NccPatch* restrict patches, const int num_patches,
    __global const int2* restrict pairs, const int num_pairs, __global float* restrict scores) {
  const int i = (int)get_global_id(0);
  if (i >= num_pairs) {
    return;
  }
  const int2 pair = pairs[i];
  if (pair.x < 0 || pair.x >= num_patches || pair.y < 0 || pair.y >= num_images) {
    scores[i] = NAN;
    return;
  }
  const NccPatch patch = patches[pair.x];
  if (patch.reference < 0 || patch.reference >= num_images) {
    scores[i] = NAN;
    return;
  }
  const NccCamera ref = cameras[patch.reference];
  const NccCamera view = cameras[pair.y];
  const float3 c = patch.center.xyz;
  const float3 n = patch.normal.xyz;

  float3 dx, dy;
  if (!patch_axes(ref, c, n, &dx, &dy)) {
    scores[i] = NAN;
    return;
  }

  float a[NCC_NUM_SAMPLES];
  float b[NCC_NUM_SAMPLES];
  const int half_size = PATCH_SIZE / 2;
  const GridProjection ga = project_grid(ref, c, dx, dy);
  const GridProjection gb = project_grid(view, c, dx, dy);
  for (int r = 0; r < PATCH_SIZE; ++r) {
    const float fr = (float)(r - half_size);
    for (int col = 0; col < PATCH_SIZE; ++col) {
      const float fc = (float)(col - half_size);
      const float va = sample_grid(images, image_table, patch.reference, ga, fr, fc);
      const float vb = sample_grid(images, image_table, pair.y, gb, fr, fc);
      // One NaN sample (outside, behind, or a NaN pixel) voids the pair.
      if (isnan(va) || isnan(vb)) {
        scores[i] = NAN;
        return;
      }
      a[r * PATCH_SIZE + col] = va;
      b[r * PATCH_SIZE + col] = vb;
    }
  }
  float w[NCC_NUM_SAMPLES];
  ncc_weights(a, w);
  scores[i] = ncc_of(a, b, w);
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
