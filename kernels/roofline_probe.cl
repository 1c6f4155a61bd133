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
// host/roofline_probe.cc, is its double twin): a window not wholly inside
// its image gives NaN; so does a window whose variance sum is below
// NCC_MIN_VARIANCE * mu^2; else the NCC clamped to [-1, 1].
//
// Build options (the host passes all of them; see sapmvs/kernel_limits.h):
//   WORK_GROUP_SIZE, PATCH_SIZE (mu, odd), NCC_MIN_VARIANCE, NCC_SIGMA_COLOR.

#ifndef WORK_GROUP_SIZE
#define WORK_GROUP_SIZE 64
#endif
#ifndef PATCH_SIZE
#define PATCH_SIZE 7
#endif
#ifndef NCC_MIN_VARIANCE
#define NCC_MIN_VARIANCE 1e-4f
#endif
#ifndef NCC_SIGMA_COLOR
#define NCC_SIGMA_COLOR 0.0f
#endif

#define NCC_NUM_SAMPLES (PATCH_SIZE * PATCH_SIZE)

// Copied verbatim from ncc_score.cl (no #include in the kernel embedding;
// tests/roofline_probe_test.cc compares the text), so that the probe does the
// scoring kernel's NCC arithmetic exactly.
// The NCC of `a` and `b` (NCC_NUM_SAMPLES values each), each sample k
// weighted by w[k] (ncc_weights), two-pass so that bright images do not lose
// the variance to cancellation; NaN when either weighted variance is below
// NCC_MIN_VARIANCE. With every weight 1 it is the plain NCC.
float ncc_of(const float* a, const float* b, const float* w) {
  float sum_w = 0.0f;
  float mean_a = 0.0f;
  float mean_b = 0.0f;
  for (int k = 0; k < NCC_NUM_SAMPLES; ++k) {
    sum_w += w[k];
    mean_a += w[k] * a[k];
    mean_b += w[k] * b[k];
  }
  mean_a /= sum_w;
  mean_b /= sum_w;
  float saa = 0.0f;
  float sbb = 0.0f;
  float sab = 0.0f;
  for (int k = 0; k < NCC_NUM_SAMPLES; ++k) {
    const float da = a[k] - mean_a;
    const float db = b[k] - mean_b;
    saa += w[k] * da * da;
    sbb += w[k] * db * db;
    sab += w[k] * da * db;
  }
  const float min_sum = NCC_MIN_VARIANCE * sum_w;
  if (!(saa >= min_sum && sbb >= min_sum)) {
    return NAN;
  }
  return clamp(sab / sqrt(saa * sbb), -1.0f, 1.0f);
}

// The weights of the reference samples `a`: 1 each when NCC_SIGMA_COLOR is
// 0, else exp(-d^2 / 2 s^2) for d the sample's difference from the centre
// sample and s = NCC_SIGMA_COLOR standard deviations of the 3 x 3 samples
// around the centre (relative, so that one setting suits dim scans and bright
// renderings alike). A window
// that straddles a wall or a roof edge then scores the surface under its
// centre more than the mixture. A flat window keeps weights 1 (and gets NaN
// from ncc_of's variance floor). native_exp (core OpenCL, not an extension):
// a weight needs a few digits only, and with exp the weighted search took
// 60 % longer than plain NCC on Herz-Jesu under PoCL (native_exp: 25 %).
void ncc_weights(const float* a, float* w) {
  if (!(NCC_SIGMA_COLOR > 0.0f)) {
    for (int k = 0; k < NCC_NUM_SAMPLES; ++k) {
      w[k] = 1.0f;
    }
    return;
  }
  // The spread of the 3 x 3 samples around the centre: the texture of the
  // centre's surface, not inflated by another surface further out.
  const int c = NCC_NUM_SAMPLES / 2;
  float mean = 0.0f;
  for (int r = -1; r <= 1; ++r) {
    for (int q = -1; q <= 1; ++q) {
      mean += a[c + r * PATCH_SIZE + q];
    }
  }
  mean /= 9.0f;
  float var = 0.0f;
  for (int r = -1; r <= 1; ++r) {
    for (int q = -1; q <= 1; ++q) {
      const float d = a[c + r * PATCH_SIZE + q] - mean;
      var += d * d;
    }
  }
  const float s = NCC_SIGMA_COLOR * sqrt(var / 9.0f);
  const float centre = a[c];
  for (int k = 0; k < NCC_NUM_SAMPLES; ++k) {
    const float d = a[k] - centre;
    w[k] = s > 0.0f ? native_exp(-0.5f * (d * d) / (s * s)) : 1.0f;
  }
}

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
