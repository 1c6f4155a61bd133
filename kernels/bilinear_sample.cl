// Bilinear interpolation of a single-channel float image at a batch of
// sub-pixel positions; the sampling primitive of the NCC kernels. See
// kernels/README.md. BilinearSampleReference (host/device/bilinear_sampler.cc) is the
// double-precision twin and must keep exactly the same border policy:
//
// - Pixel (0, 0) is the centre of the top-left pixel (OpenCV convention), so
//   pixel (c, r) covers [c - 0.5, c + 0.5] x [r - 0.5, r + 0.5].
// - A position is valid iff 0 <= x <= width - 1 and 0 <= y <= height - 1:
//   then every pixel of its 2x2 support that gets a non-zero weight is inside
//   the image. Anything else, NaN and infinite positions included, gives NaN.
//   On the last column/row the support is the cell to the left/above with
//   weight 1 on the border pixel, so exact pixel centres return the pixel.
// - NaN pixels propagate to every sample whose support contains them.
//
// Build options (the host passes all of them; see sapmvs/kernel_limits.h):
//   WORK_GROUP_SIZE  work-items per group; the launch must use exactly this.

#ifndef WORK_GROUP_SIZE
#define WORK_GROUP_SIZE 64
#endif

#include "bilinear.cl"

// values[i] = image sampled at points[i] (x, y), for i < num_points. The
// global size is rounded up to a multiple of WORK_GROUP_SIZE, hence the guard.
__kernel __attribute__((reqd_work_group_size(WORK_GROUP_SIZE, 1, 1))) void bilinear_sample(
    __global const float2* restrict points, const int num_points,
    __global const float* restrict image, const int width, const int height, const int row_pitch,
    __global float* restrict values) {
  const int i = (int)get_global_id(0);
  if (i >= num_points) {
    return;
  }
  const float2 p = points[i];
  values[i] = bilinear_at(image, width, height, row_pitch, p.x, p.y);
}
