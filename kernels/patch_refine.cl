// Batched patch refinement: one work-item per patch
// optimises the patch's depth along its reference ray and the two angles of
// its normal to maximise the mean NCC over its views, all iterations
// in-kernel. See kernels/README.md ("patch_refine.cl") for the data layout and
// the search; PatchRefineReference (host/device/patch_refiner.cc) is the
// double-precision twin and must keep exactly the same parameterisation, step
// schedule and tie rules.
//
// The NCC primitives (NccCamera, NccPatch, bilinear_at, sample_image,
// window_projection, sample_view, ncc_against, ncc_weights) come from ncc.cl, as in
// ncc_score.cl. The grid geometry of patch_views_ncc is that of the
// ncc_score kernel body.
//
// Build options (the host passes all of them; see sapmvs/kernel_limits.h):
//   WORK_GROUP_SIZE   work-items per group; the launch must use exactly this.
//   PATCH_SIZE        μ, samples per side of the patch grid (odd).
//   NCC_MIN_VARIANCE  smallest per-sample variance of a sample vector.
//   NCC_SIGMA_COLOR   > 0 weights the NCC samples (ncc_weights); 0 = plain NCC.
//   SAMPLE_STEP       spacing of the grid's samples, in reference pixels.
//   MAX_VIEWS         most views per patch (bounds the private arrays).

#ifndef WORK_GROUP_SIZE
#define WORK_GROUP_SIZE 64
#endif
#ifndef MAX_VIEWS
#define MAX_VIEWS 8
#endif

#include "ncc.cl"
#include "patch_search.cl"

// Mean NCC of the plane (c, n) seen through the reference window `win`, whose
// samples `da` are centred by ncc_centre (sum_w, saa) and weighted by w,
// against each of its `num_views` views (NCCs into `nccs`); NaN when any
// view's NCC is NaN (ncc_score's rules). With `all` false it stops at the
// first NaN view, leaving the later ones NaN: a search candidate that is
// invalid is discarded whatever its other views score.
float patch_views_ncc(__global const float* images, __global const int4* table,
                      __global const NccCamera* cameras, int reference, const int* views,
                      int num_views, const ReferenceWindow win, const float* da, const float* w,
                      float sum_w, float saa, float3 c, float3 n, bool all, float* nccs) {
  for (int v = 0; v < num_views; ++v) {
    nccs[v] = NAN;
  }
  if (!plane_seen(cameras[reference], c, n)) {
    return NAN;
  }
  float sum = 0.0f;
  bool all_valid = true;
  float b[NCC_SAMPLE_BUFFER];
  for (int v = 0; v < num_views && (all || all_valid); ++v) {
    GridProjection gb;
    const bool valid = window_projection(cameras[views[v]], win, c, n, &gb) &&
                       sample_view(images, table, views[v], gb, b);
    nccs[v] = valid ? ncc_against(da, sum_w, saa, b, w) : NAN;
    if (isnan(nccs[v])) {
      all_valid = false;
    } else {
      sum += nccs[v];
    }
  }
  return all_valid ? sum / (float)num_views : NAN;
}

// Refines patches[i] for i < num_patches against its views
// view_indices[view_offsets[i] .. view_offsets[i + 1]) (CSR; the host checks
// 1 to MAX_VIEWS views, all in range and none the reference).
//
// Parameters: t (distance from the reference centre along the ray through the
// initial centre), yaw, pitch (see normal_of). Initial steps: depth_step
// footprints (depth / f at the initial centre) for t, angle_step radians for
// both angles. Each of `iterations` rounds polls the 6 candidates
// p +- step_k e_k in the order +t, -t, +yaw, -yaw, +pitch, -pitch, starting
// from the direction that moved last, and moves to the first that strictly
// beats the current score; when none does it halves every step. The search
// ends early after max_halvings halvings (converged). Polling instead of
// scoring all 6 and taking the best: a move costs 1 to 3 scores instead of
// 6, for the same accuracy (`small`: 32 % less device time, 91.9 % of the
// points within 1 GSD against 91.8 %; city: 39 %, 76.3 % against 75.3 %).
// A candidate whose normal lies more than max_angle from the reference ray
// (cos yaw cos pitch < cos max_angle) is invalid (NaN), so the search stays
// inside the cone the matcher accepts a patch in, as PMVS2's does (its score
// is invalid once the reference sees the patch past its angle limit). A
// search free to leave the cone ended outside it on surfaces seen at grazing
// angles (Herz-Jesu-P8's forecourt), and the patch was rejected.
__kernel __attribute__((reqd_work_group_size(WORK_GROUP_SIZE, 1, 1))) void patch_refine(
    __global const float* restrict images, __global const int4* restrict image_table,
    __global const NccCamera* restrict cameras, const int num_images,
    __global const NccPatch* restrict patches, const int num_patches,
    __global const int* restrict view_offsets, __global const int* restrict view_indices,
    const int iterations, const int max_halvings, const float depth_step, const float angle_step,
    const float max_angle, __global RefinedPatchOut* restrict results,
    __global float* restrict view_scores) {
  const int i = (int)get_global_id(0);
  if (i >= num_patches) {
    return;
  }
  const NccPatch patch = patches[i];
  const int first = view_offsets[i];
  int num_views = 0;
  int views[MAX_VIEWS];
  if (!load_views(patches, i, view_offsets, view_indices, num_images, views, &num_views)) {
    results[i] = unrefined(patch);
    return;
  }
  const NccCamera ref = cameras[patch.reference];
  const float3 c0 = patch.center.xyz;
  const PatchFrame f = patch_frame(ref, c0);
  const int directions = search_directions(patch);

  float p[3];
  float step[3];
  search_start(f, patch.normal.xyz, depth_step, angle_step, p, step);
  float nccs[MAX_VIEWS];
  float trial[MAX_VIEWS];
  for (int v = 0; v < num_views; ++v) {
    nccs[v] = NAN;
  }
  // Every candidate's centre lies on the ray through c0, so all share c0's
  // reference window: sampled, weighted and centred here, once.
  ReferenceWindow win;
  float da[NCC_NUM_SAMPLES];
  float w[NCC_NUM_SAMPLES];
  float sum_w = 0.0f;
  float saa = 0.0f;
  bool window_valid = reference_window(ref, c0, &win);
  const int half_size = PATCH_SIZE / 2;
  for (int r = 0; r < PATCH_SIZE && window_valid; ++r) {
    for (int col = 0; col < PATCH_SIZE; ++col) {
      const float va = sample_reference(images, image_table, patch.reference, win,
                                        (float)(r - half_size), (float)(col - half_size));
      if (isnan(va)) {
        window_valid = false;
        break;
      }
      da[r * PATCH_SIZE + col] = va;
    }
  }
  if (window_valid) {
    ncc_weights(da, w);
    window_valid = ncc_centre(da, w, &sum_w, &saa);
  }
  // Without a valid window every candidate is NaN, and the search below
  // halves its steps to the end as the reference's does.
  const float cos_max = cos(max_angle);
  float score = NAN;
  if (window_valid && in_cone(p, cos_max)) {
    score = patch_views_ncc(images, image_table, cameras, patch.reference, views, num_views, win,
                            da, w, sum_w, saa, f.origin + p[0] * f.ray,
                            normal_of(f.e_x, f.e_y, f.e_z, p[1], p[2]), true, nccs);
  }
  int moves = 0;
  int halvings = 0;
  int evaluations = 1;
  int lead = 0;  // the direction that moved last, tried first
  for (int it = 0; it < iterations && halvings < max_halvings; ++it) {
    int moved = -1;
    for (int j = 0; j < directions && moved < 0; ++j) {
      const int k = (lead + j) % directions;
      float q[3];
      if (!poll_candidate(p, step, k, cos_max, q)) {
        continue;
      }
      const float s =
          !window_valid
              ? NAN
              : patch_views_ncc(images, image_table, cameras, patch.reference, views, num_views,
                                win, da, w, sum_w, saa, f.origin + q[0] * f.ray,
                                normal_of(f.e_x, f.e_y, f.e_z, q[1], q[2]), false, trial);
      ++evaluations;
      if (improves(s, score)) {
        moved = k;
        p[k / 2] = q[k / 2];
        score = s;
        for (int v = 0; v < num_views; ++v) {
          nccs[v] = trial[v];
        }
      }
    }
    if (moved >= 0) {
      lead = moved;
      ++moves;
    } else {
      for (int k = 0; k < 3; ++k) {
        step[k] *= 0.5f;
      }
      ++halvings;
    }
  }
  results[i] = refined(f, p, score, evaluations, moves);
  for (int v = 0; v < num_views; ++v) {
    view_scores[first + v] = nccs[v];
  }
}
