// The NCC primitives shared by ncc_score.cl, patch_refine.cl and
// roofline_probe.cl, so that the three score exactly the same arithmetic:
// the camera and patch structs, projection and sampling, the weighted NCC
// and its sample weights. NccScoreReference (host/device/ncc_scorer.cc) is the
// double-precision twin. Programs get it by `#include "ncc.cl"`, which the
// host expands when it builds them (host/device/kernel_source.h, ProgramSource).
//
// Build options it reads (the host passes all of them; see
// sapmvs/kernel_limits.h):
//   PATCH_SIZE        μ, samples per side of the patch grid (odd).
//   NCC_MIN_VARIANCE  smallest per-sample variance of a sample vector.
//   NCC_SIGMA_COLOR   > 0 weights the NCC samples (ncc_weights); 0 = plain NCC.
//   SAMPLE_STEP       spacing of the grid's samples, in reference pixels.

#ifndef SAPMVS_NCC_CL
#define SAPMVS_NCC_CL

#ifndef PATCH_SIZE
#define PATCH_SIZE 7
#endif
#ifndef NCC_MIN_VARIANCE
#define NCC_MIN_VARIANCE 1e-4f
#endif
#ifndef NCC_SIGMA_COLOR
#define NCC_SIGMA_COLOR 0.0f
#endif
#ifndef SAMPLE_STEP
#define SAMPLE_STEP 1.0f
#endif

#define NCC_NUM_SAMPLES (PATCH_SIZE * PATCH_SIZE)

// Shortest length the reference camera's x axis may keep once projected onto
// the patch plane; shorter means the plane (nearly) contains that axis and
// the in-plane grid axes are undefined. Host twin: kNccMinAxisLength.
#define NCC_MIN_AXIS_LENGTH 1e-3f

// Smallest share of its fronto-parallel length in the reference image that a
// grid axis may keep (cos of 84 degrees): a plane seen that obliquely would
// need grid steps ten times as long on it as seen face-on, and is rejected.
// Host twin: kMinForeshortening (host/match/footprint.h).
#define NCC_MIN_FORESHORTENING 0.1f

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

#include "bilinear.cl"

// Image `index` of the packed buffer sampled at (x, y). `table[index]` is
// (offset in elements, width, height, row pitch).
float sample_image(__global const float* images, __global const int4* table, int index, float x,
                   float y) {
  const int4 t = table[index];
  return bilinear_at(images + t.x, t.y, t.z, t.w, x, y);
}

// The grid axes of the patch (c, n) seen from `ref`: one sample step along
// the grid's columns (dx) and rows (dy). dx follows the reference x axis
// projected onto the plane, dy the in-plane perpendicular turned towards the
// reference y axis, so the grid follows the reference image's rows and
// columns; each is scaled so that one step projects to SAMPLE_STEP reference
// pixels at c (the Jacobian of the projection there), as PMVS's getPAxes
// does. The window then covers the reference pixels that the patch's points
// are written for whatever the plane's tilt: a step of depth / f on the
// plane squeezed an oblique plane's window to a few pixels along its slope
// (Herz-Jesu-P8's ground in front of the façade). False when c is not in
// front of the reference, the plane (nearly) contains its x axis, or an axis
// is foreshortened below NCC_MIN_FORESHORTENING.
bool patch_axes(const NccCamera ref, float3 c, float3 n, float3* dx, float3* dy) {
  const float4 o = (float4)(c, 1.0f);
  const float depth = dot(ref.p2, o);
  if (!(depth > 0.0f)) {
    return false;
  }
  const float3 x_proj = ref.x_axis.xyz - dot(ref.x_axis.xyz, n) * n;
  const float x_length = length(x_proj);
  if (!(x_length >= NCC_MIN_AXIS_LENGTH)) {
    return false;
  }
  const float3 x_dir = x_proj / x_length;
  float3 y_dir = cross(n, x_dir);
  if (dot(y_dir, ref.y_axis.xyz) < 0.0f) {
    y_dir = -y_dir;
  }
  // Reference pixels per unit length along each axis: (p0 - u p2, p1 - v p2)
  // applied to the direction, over the depth.
  const float u = dot(ref.p0, o) / depth;
  const float v = dot(ref.p1, o) / depth;
  const float3 ju = ref.p0.xyz - u * ref.p2.xyz;
  const float3 jv = ref.p1.xyz - v * ref.p2.xyz;
  const float x_pixels = length((float2)(dot(ju, x_dir), dot(jv, x_dir))) / depth;
  const float y_pixels = length((float2)(dot(ju, y_dir), dot(jv, y_dir))) / depth;
  // Fronto-parallel, both are f / depth.
  const float min_pixels = NCC_MIN_FORESHORTENING * (ref.center.w / depth);
  if (!(x_pixels >= min_pixels && y_pixels >= min_pixels)) {
    return false;
  }
  *dx = (SAMPLE_STEP / x_pixels) * x_dir;
  *dy = (SAMPLE_STEP / y_pixels) * y_dir;
  return true;
}

// The homogeneous projections of a patch grid into one camera. The grid lies
// on a plane, so projection is linear in the grid indices: the sample at
// offsets (r, col) from the centre projects to h0 + r hy + col hx. Three dot
// products per camera then replace three per sample, which was a third of a
// sample's arithmetic (bench_patch_refiner).
typedef struct {
  float3 h0;  // P [c; 1]: the centre.
  float3 hx;  // P [dx; 0]: one step along the grid's columns.
  float3 hy;  // P [dy; 0]: one step along its rows.
} GridProjection;

GridProjection project_grid(const NccCamera camera, float3 c, float3 dx, float3 dy) {
  const float4 o = (float4)(c, 1.0f);
  const float4 x = (float4)(dx, 0.0f);
  const float4 y = (float4)(dy, 0.0f);
  GridProjection g;
  g.h0 = (float3)(dot(camera.p0, o), dot(camera.p1, o), dot(camera.p2, o));
  g.hx = (float3)(dot(camera.p0, x), dot(camera.p1, x), dot(camera.p2, x));
  g.hy = (float3)(dot(camera.p0, y), dot(camera.p1, y), dot(camera.p2, y));
  return g;
}

// Image `index` at the projection of the grid sample (r, col), offsets from
// the centre; NaN when it is not strictly in front of the camera or falls
// outside the image.
float sample_grid(__global const float* images, __global const int4* table, int index,
                  const GridProjection g, float r, float col) {
  const float3 h = g.h0 + r * g.hy + col * g.hx;
  if (!(h.z > 0.0f)) {
    return NAN;
  }
  return sample_image(images, table, index, h.x / h.z, h.y / h.z);
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

#endif  // SAPMVS_NCC_CL
