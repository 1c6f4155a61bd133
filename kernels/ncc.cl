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
//   NCC_WEIGHT_MIN_SPREAD  smallest centre spread the weights scale from.
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
#ifndef NCC_WEIGHT_MIN_SPREAD
#define NCC_WEIGHT_MIN_SPREAD 2.0f
#endif
#ifndef SAMPLE_STEP
#define SAMPLE_STEP 1.0f
#endif

#define NCC_NUM_SAMPLES (PATCH_SIZE * PATCH_SIZE)
// b arrays for sample_view: 7 floats of padding for its 8-wide last store.
#define NCC_SAMPLE_BUFFER (NCC_NUM_SAMPLES + 7)

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
  float4 center;   // xyz: patch centre c (local); w ignored.
  float4 normal;   // xyz: unit normal n; w ignored.
  int reference;   // Index of the reference image R(p).
  int directions;  // The refinement's: 2 = depth only, else depth and normal.
  int reserved1, reserved2;
} NccPatch;

#include "bilinear.cl"

// Image `index` of the packed buffer sampled at (x, y). `table[index]` is
// (offset in elements, width, height, row pitch).
float sample_image(__global const float* images, __global const int4* table, int index, float x,
                   float y) {
  const int4 t = table[index];
  return bilinear_at(images + t.x, t.y, t.z, t.w, x, y);
}

// Whether the plane (c, n) can be scored from `ref`: c in front of it, the
// plane not (nearly) containing its x axis, and neither in-plane axis (the
// reference x axis projected onto the plane, and its in-plane perpendicular)
// foreshortened below NCC_MIN_FORESHORTENING of its face-on length, measured
// with the projection's Jacobian at c as PMVS's getPAxes scales its axes.
// Seen that obliquely (beyond 84 degrees), one reference pixel would stretch
// over ten face-on footprints of the plane.
bool plane_seen(const NccCamera ref, float3 c, float3 n) {
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
  const float3 y_dir = cross(n, x_dir);
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
  return x_pixels >= min_pixels && y_pixels >= min_pixels;
}

// The reference window of a patch centred at c: the PATCH_SIZE x PATCH_SIZE
// reference pixels around c's projection, SAMPLE_STEP apart along the
// image's rows and columns, and the rays through them. These are the pixels
// whose rays the host intersects with an accepted patch's plane to write its
// points, so the window scored is the window written. It depends on c's
// reference ray only, not on the plane: the refinement, which moves c along
// that ray, samples and normalises it once per patch instead of once per
// candidate and view.
typedef struct {
  float2 uv;      // c's projection: the centre sample.
  float3 ray0;    // M^-1 (u, v, 1), M = K R the reference's left 3x3: the ray
                  // to c over its depth, (c - C) / depth.
  float3 ray_x;   // SAMPLE_STEP M^-1 (1, 0, 0): the ray's change per column.
  float3 ray_y;   // SAMPLE_STEP M^-1 (0, 1, 0): its change per row.
  float3 origin;  // C, the reference's projection centre.
} ReferenceWindow;

// False when c is not in front of the reference.
bool reference_window(const NccCamera ref, float3 c, ReferenceWindow* win) {
  const float4 o = (float4)(c, 1.0f);
  const float depth = dot(ref.p2, o);
  if (!(depth > 0.0f)) {
    return false;
  }
  // The columns of M^-1 are the rows' cross products over det M.
  const float3 m0 = ref.p0.xyz;
  const float3 m1 = ref.p1.xyz;
  const float3 m2 = ref.p2.xyz;
  const float3 c12 = cross(m1, m2);
  const float scale = SAMPLE_STEP / dot(m0, c12);
  win->uv = (float2)(dot(ref.p0, o), dot(ref.p1, o)) / depth;
  win->origin = ref.center.xyz;
  win->ray0 = (c - win->origin) / depth;
  win->ray_x = scale * c12;
  win->ray_y = scale * cross(m2, m0);
  return true;
}

// The reference sample (r, col), offsets from the centre; NaN outside the
// image.
float sample_reference(__global const float* images, __global const int4* table, int index,
                       const ReferenceWindow win, float r, float col) {
  return sample_image(images, table, index, win.uv.x + SAMPLE_STEP * col,
                      win.uv.y + SAMPLE_STEP * r);
}

// The projections of a window's samples into one camera. Sample (r, col)
// lies where its reference ray meets the patch plane and projects to
// h0 + r hy + col hx (homogeneous): the plane-induced homography, linear in
// the grid indices, so that three dot products per camera replace three per
// sample.
typedef struct {
  float3 h0;  // The centre.
  float3 hx;  // One step along the window's columns.
  float3 hy;  // One step along its rows.
} GridProjection;

// The homography from the reference window onto the plane (c, n) and into
// `camera`. With d a sample's ray and k = n . (c - C), the plane meets the ray
// at C + (k / n . d) d, whose projection scaled by n . d / k is
// (n . d / k) P [C; 1] + M d: linear in d, hence in (r, col). That scale must
// stay positive over the whole window (it is 1 / depth at the centre), else
// some ray meets the plane behind the reference: false.
bool window_projection(const NccCamera camera, const ReferenceWindow win, float3 c, float3 n,
                       GridProjection* g) {
  const float k = dot(n, c - win.origin);
  const float s0 = dot(n, win.ray0) / k;
  const float sx = dot(n, win.ray_x) / k;
  const float sy = dot(n, win.ray_y) / k;
  const float half_size = (float)(PATCH_SIZE / 2);
  if (!(s0 - half_size * (fabs(sx) + fabs(sy)) > 0.0f)) {
    return false;
  }
  const float4 o = (float4)(win.origin, 1.0f);
  const float3 q = (float3)(dot(camera.p0, o), dot(camera.p1, o), dot(camera.p2, o));
  const float3 m0 = camera.p0.xyz;
  const float3 m1 = camera.p1.xyz;
  const float3 m2 = camera.p2.xyz;
  g->h0 = s0 * q + (float3)(dot(m0, win.ray0), dot(m1, win.ray0), dot(m2, win.ray0));
  g->hx = sx * q + (float3)(dot(m0, win.ray_x), dot(m1, win.ray_x), dot(m2, win.ray_x));
  g->hy = sy * q + (float3)(dot(m0, win.ray_y), dot(m1, win.ray_y), dot(m2, win.ray_y));
  return true;
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

// The samples of the grid `g` in image `index`, row by row into b, which
// holds NCC_SAMPLE_BUFFER floats; false when one of them is NaN (sample_grid's
// rules).
// The grid's image is convex where h.z stays positive (h is linear in the
// grid indices), so when its four corners lie in front of the camera and
// SAMPLE_MARGIN pixels inside the image, every sample does: the samples then
// skip the per-sample checks and are computed eight columns at a time in
// float8 (one SIMD instruction per step on a CPU, where PoCL does not
// vectorise this kernel across work-items), in the order of sample_grid's
// and bilinear_at's arithmetic (on PoCL the clouds of `small` and `campus`
// are bit for bit those of the per-sample path). On PoCL this cut
// patch_refine 7x7's device time on `campus` from 42.8 to 24.6 s.
#define SAMPLE_MARGIN 0.01f
bool sample_view(__global const float* images, __global const int4* table, int index,
                 const GridProjection g, float* b) {
  const int4 t = table[index];
  const float half_size = (float)(PATCH_SIZE / 2);
  const float x_max = (float)(t.y - 1) - SAMPLE_MARGIN;
  const float y_max = (float)(t.z - 1) - SAMPLE_MARGIN;
  bool inside = true;
  for (int k = 0; k < 4; ++k) {
    const float r = (k & 1) ? half_size : -half_size;
    const float col = (k & 2) ? half_size : -half_size;
    const float3 h = g.h0 + r * g.hy + col * g.hx;
    const float x = h.x / h.z;
    const float y = h.y / h.z;
    inside = inside && h.z > 0.0f && x >= SAMPLE_MARGIN && y >= SAMPLE_MARGIN && x <= x_max &&
             y <= y_max;
  }
  const int hs = PATCH_SIZE / 2;
  // The vector path indexes an image with int offsets: the host packs a
  // group's images in at most INT_MAX elements (UploadNccGroup).
  if (!inside) {
    for (int r = 0; r < PATCH_SIZE; ++r) {
      for (int col = 0; col < PATCH_SIZE; ++col) {
        const float v = sample_grid(images, table, index, g, (float)(r - hs), (float)(col - hs));
        if (isnan(v)) {
          return false;
        }
        b[r * PATCH_SIZE + col] = v;
      }
    }
    return true;
  }
  __global const float* image = images + t.x;
  const int8 x_cell = (int8)(max(t.y - 2, 0));
  const int8 y_cell = (int8)(max(t.z - 2, 0));
  const int8 x_last = (int8)(t.y - 1);
  const int8 y_last = (int8)(t.z - 1);
  // Eight columns at a time; lanes past the row's end repeat its last sample
  // (in the image), and their values land in b's padding.
  const float8 lane = (float8)(0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f);
  float8 any_nan = (float8)(0.0f);
  for (int r = 0; r < PATCH_SIZE; ++r) {
    const float3 hr = g.h0 + (float)(r - hs) * g.hy;
    for (int c0 = 0; c0 < PATCH_SIZE; c0 += 8) {
      const float8 col = min((float)(c0 - hs) + lane, (float8)((float)hs));
      const float8 hx = hr.x + col * g.hx.x;
      const float8 hy = hr.y + col * g.hx.y;
      const float8 hz = hr.z + col * g.hx.z;
      const float8 x = hx / hz;
      const float8 y = hy / hz;
      const int8 x0 = min(convert_int8(x), x_cell);
      const int8 y0 = min(convert_int8(y), y_cell);
      const int8 x1 = min(x0 + 1, x_last);
      const int8 y1 = min(y0 + 1, y_last);
      const float8 fx = x - convert_float8(x0);
      const float8 fy = y - convert_float8(y0);
      const int8 i00 = y0 * t.w + x0, i01 = y0 * t.w + x1;
      const int8 i10 = y1 * t.w + x0, i11 = y1 * t.w + x1;
#define GATHER8(i)                                                                       \
  (float8)(image[i.s0], image[i.s1], image[i.s2], image[i.s3], image[i.s4], image[i.s5], \
           image[i.s6], image[i.s7])
      const float8 top = (1.0f - fx) * GATHER8(i00) + fx * GATHER8(i01);
      const float8 bottom = (1.0f - fx) * GATHER8(i10) + fx * GATHER8(i11);
#undef GATHER8
      const float8 v = (1.0f - fy) * top + fy * bottom;
      vstore8(v, 0, b + r * PATCH_SIZE + c0);
      any_nan += v;
    }
  }
  const float4 s4 = any_nan.lo + any_nan.hi;
  return !isnan(s4.x + s4.y + s4.z + s4.w);
}

// The reference half of the NCC: subtracts the weighted mean of `a`
// (NCC_NUM_SAMPLES values, weights w from ncc_weights) from it in place and
// sets *sum_w and *saa, the weighted sum of its squared deviations; false
// when its weighted variance is below NCC_MIN_VARIANCE. Split from ncc_of so
// that a window scored against several views, or many candidate planes,
// is normalised once.
bool ncc_centre(float* a, const float* w, float* sum_w, float* saa) {
  float sw = 0.0f;
  float mean = 0.0f;
  for (int k = 0; k < NCC_NUM_SAMPLES; ++k) {
    sw += w[k];
    mean += w[k] * a[k];
  }
  mean /= sw;
  float ss = 0.0f;
  for (int k = 0; k < NCC_NUM_SAMPLES; ++k) {
    a[k] -= mean;
    ss += w[k] * a[k] * a[k];
  }
  *sum_w = sw;
  *saa = ss;
  return ss >= NCC_MIN_VARIANCE * sw;
}

// The NCC from a window's weighted sums (saa and sbb, the squared deviations
// of the reference and the view; sab, their products; sum_w, the weights);
// NaN when the view's variance is below NCC_MIN_VARIANCE.
float ncc_of_sums(float saa, float sbb, float sab, float sum_w) {
  if (!(sbb >= NCC_MIN_VARIANCE * sum_w)) {
    return NAN;
  }
  return clamp(sab / sqrt(saa * sbb), -1.0f, 1.0f);
}

// The NCC of a window centred by ncc_centre (`da`, sum_w, saa) and `b`,
// two-pass so that bright images do not lose the variance to cancellation;
// NaN when b's weighted variance is below NCC_MIN_VARIANCE. The sums run in
// eight float8 lanes (vload8 from the private arrays; see sample_view): on
// PoCL, 20 % less device time for the 7 x 7 refinement on `small`, with
// scores that differ from a sequential sum's in the last bits only.
float ncc_against(const float* da, float sum_w, float saa, const float* b, const float* w) {
  // Eight samples at a time, then the rest (NCC_NUM_SAMPLES % 8).
  const int vec_end = NCC_NUM_SAMPLES - NCC_NUM_SAMPLES % 8;
  float8 acc = (float8)(0.0f);
  for (int k = 0; k < vec_end; k += 8) {
    acc += vload8(0, w + k) * vload8(0, b + k);
  }
  float mean_b = 0.0f;
  for (int k = vec_end; k < NCC_NUM_SAMPLES; ++k) {
    mean_b += w[k] * b[k];
  }
  float4 a4 = acc.lo + acc.hi;
  mean_b += (a4.x + a4.y) + (a4.z + a4.w);
  mean_b /= sum_w;
  float8 bb = (float8)(0.0f);
  float8 ab = (float8)(0.0f);
  for (int k = 0; k < vec_end; k += 8) {
    const float8 db = vload8(0, b + k) - mean_b;
    const float8 wdb = vload8(0, w + k) * db;
    bb += wdb * db;
    ab += wdb * vload8(0, da + k);
  }
  float sbb = 0.0f;
  float sab = 0.0f;
  for (int k = vec_end; k < NCC_NUM_SAMPLES; ++k) {
    const float db = b[k] - mean_b;
    sbb += w[k] * db * db;
    sab += w[k] * da[k] * db;
  }
  a4 = bb.lo + bb.hi;
  sbb += (a4.x + a4.y) + (a4.z + a4.w);
  a4 = ab.lo + ab.hi;
  sab += (a4.x + a4.y) + (a4.z + a4.w);
  return ncc_of_sums(saa, sbb, sab, sum_w);
}

// The NCC of `a` and `b`, each sample k weighted by w[k]; NaN when either
// weighted variance is below NCC_MIN_VARIANCE. With every weight 1 it is the
// plain NCC. `a` is left centred (ncc_centre).
float ncc_of(float* a, const float* b, const float* w) {
  float sum_w;
  float saa;
  if (!ncc_centre(a, w, &sum_w, &saa)) {
    return NAN;
  }
  return ncc_against(a, sum_w, saa, b, w);
}

// The scale s of the sample weights: NCC_SIGMA_COLOR standard deviations of
// the 3 x 3 samples `nine` around a window's centre, row by row. Their spread
// is the texture of the centre's surface, not inflated by another surface
// further out; at least NCC_WEIGHT_MIN_SPREAD, as on weak texture it is the
// images' noise.
float ncc_weight_scale(const float* nine) {
  float mean = 0.0f;
  for (int k = 0; k < 9; ++k) {
    mean += nine[k];
  }
  mean /= 9.0f;
  float var = 0.0f;
  for (int k = 0; k < 9; ++k) {
    const float d = nine[k] - mean;
    var += d * d;
  }
  return NCC_SIGMA_COLOR * fmax(sqrt(var / 9.0f), NCC_WEIGHT_MIN_SPREAD);
}

// The weight of reference sample `a` of a window whose centre sample is
// `centre`, for the scale s of ncc_weight_scale.
float ncc_weight(float a, float centre, float s) {
  const float d = a - centre;
  return s > 0.0f ? native_exp(-0.5f * (d * d) / (s * s)) : 1.0f;
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
  const int c = NCC_NUM_SAMPLES / 2;
  float nine[9];
  for (int r = -1; r <= 1; ++r) {
    for (int q = -1; q <= 1; ++q) {
      nine[(r + 1) * 3 + q + 1] = a[c + r * PATCH_SIZE + q];
    }
  }
  const float s = ncc_weight_scale(nine);
  for (int k = 0; k < NCC_NUM_SAMPLES; ++k) {
    w[k] = ncc_weight(a[k], a[c], s);
  }
}

#endif  // SAPMVS_NCC_CL
