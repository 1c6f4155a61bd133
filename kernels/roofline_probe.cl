// Roofline probe: the best rates this device reaches on what the matcher's
// kernels do, to judge them against (profiling/bench_ncc_scorer reports the
// scoring kernel as a fraction of these; see kernels/README.md).
//
//   copy_float4  dst[i] = src[i]: the memory bandwidth the device sustains.
//   ncc_window   NCC of mu x mu windows at integer corners of two images,
//                read straight from memory: ncc_score's arithmetic without
//                the projection, the bilinear interpolation or scattered
//                reads, i.e. the most NCC evaluations per second a kernel
//                of this shape can reach here.
//
// ncc_window's result follows ncc_score's policy (RooflineProbe's reference,
// host/device/roofline_probe.cc, is its double twin): a window not wholly inside
// its image gives NaN; so does a window whose variance sum is below
// NCC_MIN_VARIANCE * mu^2; else the NCC clamped to [-1, 1].
//
// Build options (the host passes all of them; see sapmvs/kernel_limits.h):
//   WORK_GROUP_SIZE, PATCH_SIZE (mu, odd), NCC_MIN_VARIANCE, NCC_SIGMA_COLOR.

#ifndef WORK_GROUP_SIZE
#define WORK_GROUP_SIZE 64
#endif

// The NCC arithmetic of the scoring kernels, from the same source.
#include "ncc.cl"

__kernel __attribute__((reqd_work_group_size(WORK_GROUP_SIZE, 1, 1))) void copy_float4(
    __global const float4* restrict src, __global float4* restrict dst, const int n) {
  const int i = (int)get_global_id(0);
  if (i < n) {
    dst[i] = src[i];
  }
}

// corners[i] = (xa, ya, xb, yb): top-left pixels of the window in a and in b.
__kernel __attribute__((reqd_work_group_size(WORK_GROUP_SIZE, 1, 1))) void ncc_window(
    __global const float* restrict a, __global const float* restrict b, const int width,
    const int height, __global const int4* restrict corners, const int n,
    __global float* restrict scores) {
  const int i = (int)get_global_id(0);
  if (i >= n) {
    return;
  }
  const int4 c = corners[i];
  if (c.x < 0 || c.y < 0 || c.z < 0 || c.w < 0 || c.x > width - PATCH_SIZE ||
      c.z > width - PATCH_SIZE || c.y > height - PATCH_SIZE || c.w > height - PATCH_SIZE) {
    scores[i] = NAN;
    return;
  }
  float va[NCC_NUM_SAMPLES];
  float vb[NCC_NUM_SAMPLES];
  for (int r = 0; r < PATCH_SIZE; ++r) {
    __global const float* row_a = a + (size_t)(c.y + r) * (size_t)width + c.x;
    __global const float* row_b = b + (size_t)(c.w + r) * (size_t)width + c.z;
    for (int k = 0; k < PATCH_SIZE; ++k) {
      va[r * PATCH_SIZE + k] = row_a[k];
      vb[r * PATCH_SIZE + k] = row_b[k];
    }
  }
  float w[NCC_NUM_SAMPLES];
  ncc_weights(va, w);
  scores[i] = ncc_of(va, vb, w);
}
