// The bilinear sampling primitive, shared by every kernel that samples an
// image: bilinear_sample.cl (which states the border policy and has the
// double-precision twin) and, through ncc.cl, the NCC kernels. Programs get
// it by `#include "bilinear.cl"`, which the host expands when it builds them
// (host/device/kernel_source.h, ProgramSource); the guard keeps one definition when
// a program reaches it twice.

#ifndef SAPMVS_BILINEAR_CL
#define SAPMVS_BILINEAR_CL

// Bilinear value of `image` at (x, y) under bilinear_sample.cl's policy. `row_pitch` is
// the distance between rows in elements (>= width).
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

#endif  // SAPMVS_BILINEAR_CL
