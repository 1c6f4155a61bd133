// Batched NCC scoring of PMVS patches (method.md 3.1): one work-item per
// (patch, view) pair. See kernels/README.md for the data layout; the host
// mirrors of the structs below are in host/ncc_scorer.h (with static_asserts on
// their layout), and NccScoreReference (host/ncc_scorer.cc) is the
// double-precision twin that must keep exactly the same geometry and NaN rules.
//
// All coordinates are local (relative to the block's origin), in float32.
//
// Build options (the host passes all of them; see sapmvs/kernel_limits.h):
//   WORK_GROUP_SIZE   work-items per group; the launch must use exactly this.
//   PATCH_SIZE        μ, samples per side of the patch grid (odd).
//   NCC_MIN_VARIANCE  smallest per-sample variance of a sample vector.
//   NCC_SIGMA_COLOR   > 0 weights the NCC samples (ncc_weights); 0 = plain NCC.

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

// Shortest length the reference camera's x axis may keep once projected onto
// the patch plane; shorter means the plane (nearly) contains that axis and
// the in-plane grid axes are undefined. Host twin: kNccMinAxisLength.
#define NCC_MIN_AXIS_LENGTH 1e-3f

// One image's camera (host: NccCamera, 96 bytes).
typedef struct {
  float4 p0, p1, p2;  // Rows of the 3x4 projection matrix K [R | t], local frame.
  float4 x_axis;      // Camera x axis in the world (row 0 of R_wc); w = 0.
  float4 y_axis;      // Camera y axis in the world (row 1 of R_wc); w = 0.
  float4 center;      // xyz: projection centre (local); w: mean focal length, pixels.
} NccCamera;

// One patch (host: NccPatch, 48 bytes).
typedef struct {
  float4 center;  // xyz: patch centre c (local); w ignored.
  float4 normal;  // xyz: unit normal n; w ignored.
  int reference;  // Index of the reference image R(p).
  int reserved0, reserved1, reserved2;
} NccPatch;

// Copied verbatim from bilinear_sample.cl, because the kernel embedding has no
// #include: keep the two identical (tests/ncc_scorer_test.cc compares the
// text). Bilinear value of `image` at (x, y); NaN unless 0 <= x <= width - 1
// and 0 <= y <= height - 1.
float bilinear_at(__global const float* image, int width, int height, int row_pitch, float x,
                  float y) {
  // Written negated so that NaN coordinates, which compare false, are rejected.
  if (!(x >= 0.0f && y >= 0.0f && x <= (float)(width - 1) && y <= (float)(height - 1))) {
    return NAN;
  }
  // Clamping the cell keeps x == width - 1 from reading column `width`; the
  // fraction then becomes 1 (or 0 for a 1-pixel-wide image, where x1 == x0).
  const int x0 = min((int)x, max(width - 2, 0));
  const int y0 = min((int)y, max(height - 2, 0));
  const int x1 = min(x0 + 1, width - 1);
  const int y1 = min(y0 + 1, height - 1);
  const float fx = x - (float)x0;
  const float fy = y - (float)y0;
  __global const float* row0 = image + (size_t)y0 * (size_t)row_pitch;
  __global const float* row1 = image + (size_t)y1 * (size_t)row_pitch;
  // (1 - f) * a + f * b rather than a + f * (b - a): exact at f = 0 and f = 1,
  // so pixel centres reproduce the pixel bit for bit.
  const float top = (1.0f - fx) * row0[x0] + fx * row0[x1];
  const float bottom = (1.0f - fx) * row1[x0] + fx * row1[x1];
  return (1.0f - fy) * top + fy * bottom;
}

// Image `index` of the packed buffer sampled at (x, y). `table[index]` is
// (offset in elements, width, height, row pitch).
float sample_image(__global const float* images, __global const int4* table, int index, float x,
                   float y) {
  const int4 t = table[index];
  return bilinear_at(images + t.x, t.y, t.z, t.w, x, y);
}

// `camera` sampled at the projection of the local point `X`; NaN when `X` is
// not strictly in front of the camera or projects outside the image.
float sample_projection(__global const float* images, __global const int4* table, int index,
                        const NccCamera camera, float3 X) {
  const float4 h = (float4)(X, 1.0f);
  const float w = dot(camera.p2, h);
  if (!(w > 0.0f)) {
    return NAN;
  }
  return sample_image(images, table, index, dot(camera.p0, h) / w, dot(camera.p1, h) / w);
}

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

  // Grid spacing: the footprint of one reference pixel at c, depth / f (the
  // third row of K [R | t] gives the depth along the optical axis).
  const float depth = dot(ref.p2, (float4)(c, 1.0f));
  if (!(depth > 0.0f)) {
    scores[i] = NAN;
    return;
  }
  const float step = depth / ref.center.w;
  // In-plane axes: the reference x axis projected onto the plane, and the
  // in-plane perpendicular turned towards the reference y axis, so the grid
  // follows the reference image's rows and columns (as PMVS's getPAxes).
  const float3 x_proj = ref.x_axis.xyz - dot(ref.x_axis.xyz, n) * n;
  const float x_length = length(x_proj);
  if (!(x_length >= NCC_MIN_AXIS_LENGTH)) {
    scores[i] = NAN;
    return;
  }
  const float3 x_dir = x_proj / x_length;
  float3 y_dir = cross(n, x_dir);
  if (dot(y_dir, ref.y_axis.xyz) < 0.0f) {
    y_dir = -y_dir;
  }
  const float3 dx = step * x_dir;
  const float3 dy = step * y_dir;

  float a[NCC_NUM_SAMPLES];
  float b[NCC_NUM_SAMPLES];
  const int half_size = PATCH_SIZE / 2;
  for (int r = 0; r < PATCH_SIZE; ++r) {
    const float3 row = c + (float)(r - half_size) * dy;
    for (int col = 0; col < PATCH_SIZE; ++col) {
      const float3 X = row + (float)(col - half_size) * dx;
      const float va = sample_projection(images, image_table, patch.reference, ref, X);
      const float vb = sample_projection(images, image_table, pair.y, view, X);
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
