// What the two refinement kernels share: their output record, the search's
// frame and the normal of a search point, the tie rule and the guards. patch_refine.cl searches
// each patch in one work-item, patch_refine_group.cl in one work-group; both run the same search
// (PatchRefineReference in host/device/patch_refiner.cc is its double-precision twin). Included,
// never built on its own.

#ifndef SAPMVS_PATCH_SEARCH_CL
#define SAPMVS_PATCH_SEARCH_CL

// One refined patch (host: RefinedPatchOut, 48 bytes).
typedef struct {
  float4 center;  // xyz: refined centre; w: mean NCC over the views (NaN: none valid).
  float4 normal;  // xyz: refined unit normal; w: candidates scored, the start included.
  float4 params;  // x: depth offset along the ray from the start, in footprints;
                  // y: yaw, z: pitch (radians); w: accepted moves.
} RefinedPatchOut;

// The normal of (yaw, pitch) in a patch's frame (PatchFrame) is
//   cos(pitch) sin(yaw) e_x + sin(pitch) e_y + cos(pitch) cos(yaw) e_z.
float3 normal_of(float3 e_x, float3 e_y, float3 e_z, float yaw, float pitch) {
  const float cp = cos(pitch);
  return (cp * sin(yaw)) * e_x + sin(pitch) * e_y + (cp * cos(yaw)) * e_z;
}

// True when `score` beats `best`: valid, and best is NaN or strictly lower.
bool improves(float score, float best) { return !isnan(score) && (isnan(best) || score > best); }

// A patch's search frame: e_z points from the start c0 towards the reference
// camera, e_x is the reference x axis made orthogonal to e_z, e_y = e_z x e_x.
// A search point (t, yaw, pitch) is the centre origin + t ray and the normal
// normal_of(yaw, pitch).
typedef struct {
  float3 origin;  // the reference's projection centre C
  float3 ray;     // unit ray from C through c0
  float3 e_x, e_y, e_z;
  float t0;         // |c0 - C|
  float footprint;  // depth / f of the reference at c0
} PatchFrame;

PatchFrame patch_frame(const NccCamera ref, float3 c0) {
  PatchFrame f;
  f.origin = ref.center.xyz;
  f.t0 = length(c0 - f.origin);
  f.ray = (c0 - f.origin) / f.t0;
  f.e_z = -f.ray;
  f.e_x = normalize(ref.x_axis.xyz - dot(ref.x_axis.xyz, f.e_z) * f.e_z);
  f.e_y = cross(f.e_z, f.e_x);
  f.footprint = dot(ref.p2, (float4)(c0, 1.0f)) / ref.center.w;
  return f;
}

// Patch i's views into `views`, their count into *num_views; false when the
// patch's reference or a view is out of range or the count is not 1 to
// MAX_VIEWS (guards only: the host rejects all of these before enqueueing).
bool load_views(__global const NccPatch* patches, int i, __global const int* view_offsets,
                __global const int* view_indices, int num_images, int* views, int* num_views) {
  const int first = view_offsets[i];
  *num_views = view_offsets[i + 1] - first;
  if (patches[i].reference < 0 || patches[i].reference >= num_images || *num_views < 1 ||
      *num_views > MAX_VIEWS) {
    return false;
  }
  for (int v = 0; v < *num_views; ++v) {
    views[v] = view_indices[first + v];
    if (views[v] < 0 || views[v] >= num_images) {
      return false;
    }
  }
  return true;
}

// The record of a patch left as it came (score NaN, nothing scored).
RefinedPatchOut unrefined(const NccPatch patch) {
  RefinedPatchOut out;
  out.center = (float4)(patch.center.xyz, NAN);
  out.normal = (float4)(patch.normal.xyz, 0.0f);
  out.params = (float4)(0.0f, 0.0f, 0.0f, 0.0f);
  return out;
}

// The record of the search point p = (t, yaw, pitch) in frame f.
RefinedPatchOut refined(const PatchFrame f, const float* p, float score, int evaluations,
                        int moves) {
  RefinedPatchOut out;
  out.center = (float4)(f.origin + p[0] * f.ray, score);
  out.normal = (float4)(normal_of(f.e_x, f.e_y, f.e_z, p[1], p[2]), (float)evaluations);
  out.params = (float4)((p[0] - f.t0) / f.footprint, p[1], p[2], (float)moves);
  return out;
}

// The search's start: p = (t0, yaw0, pitch0) of the normal n0 in frame f,
// and its first steps (depth_step footprints, angle_step radians).
void search_start(const PatchFrame f, float3 n0, float depth_step, float angle_step, float* p,
                  float* step) {
  p[0] = f.t0;
  p[1] = atan2(dot(n0, f.e_x), dot(n0, f.e_z));
  p[2] = asin(clamp(dot(n0, f.e_y), -1.0f, 1.0f));
  step[0] = depth_step * f.footprint;
  step[1] = angle_step;
  step[2] = angle_step;
}

// Whether the normal of search point p lies inside the cone of the reference
// ray whose half-angle has the cosine cos_max.
bool in_cone(const float* p, float cos_max) { return cos(p[1]) * cos(p[2]) >= cos_max; }

// The search directions of a patch: 2 (+t, -t) or all 6.
int search_directions(const NccPatch patch) { return patch.directions == 2 ? 2 : 6; }

// Candidate k (+t, -t, +yaw, -yaw, +pitch, -pitch) around p into q; false when
// its normal lies outside the cone (in_cone).
bool poll_candidate(const float* p, const float* step, int k, float cos_max, float* q) {
  q[0] = p[0];
  q[1] = p[1];
  q[2] = p[2];
  q[k / 2] += (k % 2 == 0) ? step[k / 2] : -step[k / 2];
  return in_cone(q, cos_max);
}

#endif  // SAPMVS_PATCH_SEARCH_CL
