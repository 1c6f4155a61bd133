// Batched patch refinement, one work-group per patch: patch_refine.cl's
// search (same parameters, steps, polling order, tie rules and outputs;
// PatchRefineReference is the twin of both), with the window's samples
// spread over the group's work-items and each NCC's sums reduced in local
// memory. patch_refine's one work-item per patch suits a CPU, where PoCL runs
// a group's items in a loop and each item's rows in SIMD. On a GPU a launch
// of a few hundred patches filled a few multiprocessors, each patch searched
// in series by one lane, its window spilled from registers: on an H200,
// Herz-Jesu-P8's 15 x 15 and 21 x 21 polish took 0.70 and 0.43 s against 0.31
// and 0.17 s on two CPU cores.
//
// Every work-item of a group runs the same search: the sums come back to all
// of them from local memory, so their scores, moves and branches agree, and
// every barrier is reached by the whole group. The sums add in a tree, not in
// patch_refine's order, so scores differ from its in the last bits.
//
// Build options: those of patch_refine.cl, with WORK_GROUP_SIZE the work-items
// of one patch, a power of two (kernel_limits.h, RefineGroupWorkItems).

#ifndef WORK_GROUP_SIZE
#define WORK_GROUP_SIZE 64
#endif
#ifndef MAX_VIEWS
#define MAX_VIEWS 8
#endif

#include "ncc.cl"
#include "patch_search.cl"

// Samples of the window each work-item holds: k = lid + j WORK_GROUP_SIZE.
#define SAMPLES_PER_ITEM ((NCC_NUM_SAMPLES + WORK_GROUP_SIZE - 1) / WORK_GROUP_SIZE)

// The sum of x over the work-group, returned to each of its work-items; each
// must call it. Unrolled, so that its barriers are straight-line code: PoCL
// (which runs this kernel in the tests) compiles barriers in nested loops
// into code that took minutes to build.
float2 group_sum2(float2 x, __local float2* scratch) {
  const int lid = (int)get_local_id(0);
  barrier(CLK_LOCAL_MEM_FENCE);  // the last sum's readers are done with scratch[0]
  scratch[lid] = x;
  barrier(CLK_LOCAL_MEM_FENCE);
#define SAPMVS_REDUCE_STEP(stride)             \
  if ((stride) < WORK_GROUP_SIZE) {            \
    if (lid < (stride)) {                      \
      scratch[lid] += scratch[lid + (stride)]; \
    }                                          \
    barrier(CLK_LOCAL_MEM_FENCE);              \
  }
  SAPMVS_REDUCE_STEP(128)
  SAPMVS_REDUCE_STEP(64)
  SAPMVS_REDUCE_STEP(32)
  SAPMVS_REDUCE_STEP(16)
  SAPMVS_REDUCE_STEP(8)
  SAPMVS_REDUCE_STEP(4)
  SAPMVS_REDUCE_STEP(2)
  SAPMVS_REDUCE_STEP(1)
#undef SAPMVS_REDUCE_STEP
  return scratch[0];
}

// patch_refine's kernel, patch i = get_group_id(0); the launch's global size
// is num_patches x WORK_GROUP_SIZE. Work-item 0 writes the results.
__kernel __attribute__((reqd_work_group_size(WORK_GROUP_SIZE, 1, 1))) void patch_refine_group(
    __global const float* restrict images, __global const int4* restrict image_table,
    __global const NccCamera* restrict cameras, const int num_images,
    __global const NccPatch* restrict patches, const int num_patches,
    __global const int* restrict view_offsets, __global const int* restrict view_indices,
    const int iterations, const int max_halvings, const float depth_step, const float angle_step,
    const float max_angle, __global RefinedPatchOut* restrict results,
    __global float* restrict view_scores) {
  __local float window[NCC_NUM_SAMPLES];
  __local float2 scratch[WORK_GROUP_SIZE];
  const int i = (int)get_group_id(0);
  const int lid = (int)get_local_id(0);
  if (i >= num_patches) {
    return;
  }
  const NccPatch patch = patches[i];
  const int first = view_offsets[i];
  int num_views = 0;
  int views[MAX_VIEWS];
  if (!load_views(patches, i, view_offsets, view_indices, num_images, views, &num_views)) {
    if (lid == 0) {
      results[i] = unrefined(patch);
    }
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
  // The reference window, sampled, weighted and centred once (patch_refine's
  // reasons): each work-item its share, all of it in `window` for the weights.
  const int hs = PATCH_SIZE / 2;
  ReferenceWindow win;
  const bool in_front = reference_window(ref, c0, &win);
  float off_image = 0.0f;
  for (int j = 0; j < SAMPLES_PER_ITEM && in_front; ++j) {
    const int k = lid + j * WORK_GROUP_SIZE;
    if (k < NCC_NUM_SAMPLES) {
      const float va = sample_reference(images, image_table, patch.reference, win,
                                        (float)(k / PATCH_SIZE - hs), (float)(k % PATCH_SIZE - hs));
      window[k] = va;
      off_image += isnan(va) ? 1.0f : 0.0f;
    }
  }
  const float missing = group_sum2((float2)(off_image, 0.0f), scratch).x;
  bool window_valid = in_front && missing == 0.0f;
  // group_sum2's barriers also make `window` whole for every work-item.
  float da[SAMPLES_PER_ITEM];
  float w[SAMPLES_PER_ITEM];
  // ncc_weights, each work-item for its samples.
  const int centre = NCC_NUM_SAMPLES / 2;
  float nine[9];
  for (int r = -1; r <= 1; ++r) {
    for (int q = -1; q <= 1; ++q) {
      nine[(r + 1) * 3 + q + 1] = window_valid ? window[centre + r * PATCH_SIZE + q] : 0.0f;
    }
  }
  const float scale = NCC_SIGMA_COLOR > 0.0f ? ncc_weight_scale(nine) : 0.0f;
  float2 part = (float2)(0.0f);  // x: sum of w; y: sum of w a
  for (int j = 0; j < SAMPLES_PER_ITEM; ++j) {
    const int k = lid + j * WORK_GROUP_SIZE;
    da[j] = 0.0f;
    w[j] = 0.0f;
    if (k < NCC_NUM_SAMPLES && window_valid) {
      da[j] = window[k];
      w[j] = NCC_SIGMA_COLOR > 0.0f ? ncc_weight(da[j], nine[4], scale) : 1.0f;
      part += (float2)(w[j], w[j] * da[j]);
    }
  }
  // ncc_centre: the weighted mean off, then the variance floor.
  const float2 sums = group_sum2(part, scratch);
  const float sum_w = sums.x;
  const float mean_a = sums.y / sum_w;
  float ss = 0.0f;
  for (int j = 0; j < SAMPLES_PER_ITEM; ++j) {
    da[j] -= mean_a;
    ss += w[j] * da[j] * da[j];
  }
  const float saa = group_sum2((float2)(ss, 0.0f), scratch).x;
  window_valid = window_valid && saa >= NCC_MIN_VARIANCE * sum_w;

  // The search of patch_refine, as one loop that scores one view of one
  // candidate plane per pass (two sums, so every pass has the same barriers
  // for PoCL's sake). Between passes, the bookkeeping picks the next
  // candidate: patch_refine's polling, steps and tie rules, in its order.
  const float cos_max = cos(max_angle);
  float score = NAN;
  int moves = 0;
  int halvings = 0;
  int evaluations = 1;
  int lead = 0;          // the direction that moved last, tried first
  int it = 0;            // search rounds done
  int polled = 0;        // candidates of this round polled
  int moved = -1;        // this round's move, once one beat the score
  bool started = false;  // the start has been scored (or could not be)
  bool scoring = false;  // a candidate's views are being scored
  int k = -1;            // its direction; -1: the start
  bool all = false;      // score every view, not stop at the first NaN
  float q[3] = {p[0], p[1], p[2]};
  float3 cc = (float3)(0.0f);
  float3 cn = (float3)(0.0f);
  int v = 0;  // the view being scored
  float sum = 0.0f;
  bool all_valid = true;
  bool done = false;
  // One exit, at the top, and the same barriers on every pass: PoCL's
  // compiler rejects other shapes of a loop with barriers.
  while (!done) {
    // Pick the next candidate when none is being scored; stop when none is
    // left (the last pass then sums nothing, for the barriers' sake).
    while (!scoring && !done) {
      if (!started) {
        started = true;
        if (!(window_valid && in_cone(p, cos_max))) {
          continue;
        }
        k = -1;
        all = true;
      } else {
        if (polled == directions || moved >= 0) {
          if (moved >= 0) {
            lead = moved;
            ++moves;
          } else {
            for (int e = 0; e < 3; ++e) {
              step[e] *= 0.5f;
            }
            ++halvings;
          }
          ++it;
          polled = 0;
          moved = -1;
          continue;
        }
        if (polled == 0 && !(it < iterations && halvings < max_halvings)) {
          done = true;
          continue;
        }
        k = (lead + polled) % directions;
        ++polled;
        if (!poll_candidate(p, step, k, cos_max, q)) {
          continue;
        }
        ++evaluations;
        if (!window_valid) {
          continue;  // NaN: improves nothing
        }
        all = false;
      }
      const float* at = k < 0 ? p : q;
      cc = f.origin + at[0] * f.ray;
      cn = normal_of(f.e_x, f.e_y, f.e_z, at[1], at[2]);
      for (int u = 0; u < num_views; ++u) {
        trial[u] = NAN;
      }
      if (!plane_seen(ref, cc, cn)) {
        continue;  // NaN: improves nothing (the start's score stays NaN)
      }
      v = 0;
      sum = 0.0f;
      all_valid = true;
      scoring = true;
    }
    // View v of the candidate (cc, cn): its samples, then the NCC's sums.
    GridProjection gb;
    const bool projected =
        !done && window_projection(cameras[views[min(v, num_views - 1)]], win, cc, cn, &gb);
    float b[SAMPLES_PER_ITEM];
    float2 part = (float2)(0.0f);  // x: sum of w b; y: samples missing
    for (int j = 0; j < SAMPLES_PER_ITEM; ++j) {
      const int kk = lid + j * WORK_GROUP_SIZE;
      b[j] = NAN;
      if (kk < NCC_NUM_SAMPLES) {
        if (projected) {
          b[j] = sample_grid(images, image_table, views[v], gb, (float)(kk / PATCH_SIZE - hs),
                             (float)(kk % PATCH_SIZE - hs));
        }
        if (isnan(b[j])) {
          part.y += 1.0f;
        } else {
          part.x += w[j] * b[j];
        }
      }
    }
    const float2 sb = group_sum2(part, scratch);
    const float mean_b = sb.x / sum_w;
    float2 dev = (float2)(0.0f);  // x: sum of w db^2; y: sum of w da db
    for (int j = 0; j < SAMPLES_PER_ITEM; ++j) {
      if (!isnan(b[j])) {
        const float db = b[j] - mean_b;
        const float wdb = w[j] * db;
        dev += (float2)(wdb * db, wdb * da[j]);
      }
    }
    const float2 sd = group_sum2(dev, scratch);
    if (!done) {
      const float ncc = sb.y == 0.0f ? ncc_of_sums(saa, sd.x, sd.y, sum_w) : NAN;
      trial[v] = ncc;
      if (isnan(ncc)) {
        all_valid = false;
      } else {
        sum += ncc;
      }
      ++v;
      if (!(v < num_views && (all || all_valid))) {
        // The candidate is scored (NaN when a view was not).
        scoring = false;
        const float s = all_valid ? sum / (float)num_views : NAN;
        if (k < 0) {
          score = s;
          for (int u = 0; u < num_views; ++u) {
            nccs[u] = trial[u];
          }
        } else if (improves(s, score)) {
          moved = k;
          p[k / 2] = q[k / 2];
          score = s;
          for (int u = 0; u < num_views; ++u) {
            nccs[u] = trial[u];
          }
        }
      }
    }
  }
  if (lid == 0) {
    results[i] = refined(f, p, score, evaluations, moves);
    for (int v = 0; v < num_views; ++v) {
      view_scores[first + v] = nccs[v];
    }
  }
}
