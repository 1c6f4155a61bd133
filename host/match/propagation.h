#pragma once
// The patch queue and the cell grids (method.md 3.8, 4.1). Accepted patches
// emit points into empty cells of their reference image and mark the cells
// their points fall in in every photo-consistent view; their neighbourhood
// becomes the next wave's candidates:
//   sapmvs: an L x L patch emits one point per reference pixel of its window
//           (flood-filled from the centre, stopped by matched edges that are
//           off the patch plane and by pixels its weighted NCC hardly
//           counted, see WindowPixels) and seeds new candidates just beyond
//           its extent in 8 directions; after each expansion its plane is
//           fitted to its neighbours' centres (plane_refit.h) and its points
//           are moved onto it, or cut back to its centre where none confirm it;
//   pmvs:   a patch emits its centre and expands into the 4 neighbouring
//           empty cells (PMVS's expansion in the patch plane).
// sapmvs mode's last MatcherOptions::pmvs_passes passes grow as pmvs mode
// does, from every point (GrowAsPmvs).
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>
#include <unordered_map>
#include <vector>

#include "match/group_data.h"
#include "match/patch_engine.h"
#include "match/seed_matcher.h"
#include "sapmvs/match/ground_region.h"

namespace sapmvs {

struct DensePoint {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();   // local frame
  int patch = -1;                                // index into Propagator::patches()
  Eigen::Vector2f uv = Eigen::Vector2f::Zero();  // reference pixel
};

// Matched edge points of one image: where `matched` is set, `points` holds
// the edge's 3D point (local frame) under the key y * cols + x. Sparse: a
// dense 3-float image per image was 12 bytes a pixel for the few percent of
// pixels that are matched edges.
struct EdgeMap {
  cv::Mat matched;  // CV_8U, 255 = matched edge pixel
  std::unordered_map<int, Eigen::Vector3f> points;
};

class Propagator {
 public:
  Propagator(const MatchGroupData& group, const MatcherOptions& options, PatchEngine& engine);

  // Tries each feature's candidates in order, one batch per rank, keeping
  // the first accepted; accepted seeds join the front. May follow waves:
  // a seed whose cell a patch holds by then is not tried.
  // `on_rank(rank, ranks, accepted)` after each rank of candidates is scored.
  void RunSeeds(const std::vector<SeedFeature>& seeds,
                const std::function<void(long, long, long)>& on_rank = {});
  // True when the cell of pixel uv of `image` is inside it and empty: where
  // a seed or a wave's candidate is still worth trying.
  bool CellFree(int image, const Eigen::Vector2d& uv) const;
  // The ground the group owns: no seed or candidate whose centre lies
  // outside it is tried, so no patch grows there. Everything by default.
  void SetRegion(const GroundRegion& region) { region_ = region; }
  // Edge barriers for the flood fill (sapmvs mode); one map per image.
  void SetEdges(std::vector<EdgeMap> edges) { edges_ = std::move(edges); }
  // Waves until the front is empty (or max_waves). `on_wave` (may be empty)
  // is called after each wave with its number, its size and the points. A
  // wave takes its candidates best parent first, and one whose centre lies
  // within half a window of an earlier one's in the same image waits for the
  // next wave (Crowded): evaluated together, both were refined and accepted,
  // and the second found its cells taken by the first. If the first fails,
  // the second is tried next. On `small` and `city` at level 1 this cut the
  // candidates refined by a fifth and the wall by 8-9 %, with coverage of
  // the truth 79.8 / 75.3 % against 80.2 / 75.8 % and the points within
  // 1 GSD 91.7 / 89.6 % against 91.7 / 89.8 % (taking them oldest first
  // instead of best parent first: 79.6 / 75.3 %).
  void RunWaves(const std::function<void(long, long, long)>& on_wave);
  // Drops the points where keep[i] is false and frees their cells in every
  // grid, then queues the expansion of every patch that still has points
  // (PMVS's expand-filter iterations: the ground a false patch held is open
  // to its neighbours' planes again), or after GrowAsPmvs every point's rim.
  // The freed cells may be tried again.
  void Prune(const std::vector<bool>& keep);
  // sapmvs mode: fits each patch's plane to its neighbours' centres
  // (FitPatchNormals), moves its points onto the fitted plane, and keeps only
  // those within kUnfittedReach pixels of the centre of a patch whose plane
  // none confirms. The cells of the dropped points are freed; with
  // MatcherOptions::refill_cut a patch cut back is expanded from its centre
  // into the front (which the next RunWaves takes), as it is by every later
  // Prune.
  // Returns the points dropped. No-op in pmvs mode, whose patches emit their
  // centres only, and with refit_neighbours = 0.
  long RefitPlanes();
  // From here on candidates are evaluated by `engine` and accepted patches
  // emit and expand as in pmvs mode (MatcherOptions::pmvs_passes), and
  // Prune queues, for every point, the empty cells beside its reference
  // cell (4, as PMVS's), each a candidate on the point's patch plane: the
  // rims of the adaptive patches, inside and out, where their centres'
  // neighbouring cells are their own points'.
  void GrowAsPmvs(PatchEngine& engine);

  const std::vector<AcceptedPatch>& patches() const { return patches_; }
  const std::vector<DensePoint>& points() const { return points_; }
  long seeds_tried() const { return seeds_tried_; }
  long seeds_accepted() const { return seeds_accepted_; }
  long candidates() const { return candidates_; }
  long waves() const { return waves_; }
  long largest_wave() const { return largest_wave_; }
  // Points emitted so far, including those Prune dropped.
  long emitted() const { return emitted_; }
  // Depths of the accepted seeds, per image (for the edge search range).
  const std::vector<std::vector<double>>& seed_depths() const { return seed_depths_; }

 private:
  struct Grid {
    int cols = 0, rows = 0;
    std::vector<int> owner;                                // patch index, -1 = empty
    std::vector<uint8_t> tries;                            // candidates started in the cell
    int Index(const Eigen::Vector2d& uv, int cell) const;  // -1 outside
    // Appends the cells 4-connected to `cell` (none for -1) inside the grid.
    void Beside(int cell, std::vector<int>* out) const;
    // The pixel at the centre of `cell`, cs pixels a side.
    Eigen::Vector2d Centre(int cell, int cs) const;
  };
  // What a patch would emit: its points (local frame, reference pixel), the
  // reference cell of each, and the cell each lands in in each of the
  // patch's views, view_cells[v * points.size() + k] (-1 outside or behind).
  // covers: the group's other reference images that see the patch though
  // not among its views (a group larger than a view list), cover_cells their
  // cells as view_cells.
  struct EmitPlan {
    std::vector<DensePoint> points;
    std::vector<int> ref_cells;
    std::vector<int> view_cells;
    std::vector<int> covers;
    std::vector<int> cover_cells;
  };
  EmitPlan PlanEmit(const AcceptedPatch& patch) const;
  // Emits the planned points of `patch` whose reference cells are still
  // free; returns false (and stores nothing) when no cell was left for it.
  bool Emit(const AcceptedPatch& patch, const EmitPlan& plan);
  void Expand(int patch_index, std::vector<PatchCandidate>* front);
  // Queues a candidate on `patch`'s plane at pixel q of `image` (its
  // reference by default), with that image as its reference, unless q's
  // cell is outside, covered or tried kMaxCellTries times.
  void Offer(const AcceptedPatch& patch, const Eigen::Vector2d& q,
             std::vector<PatchCandidate>* front, int image = -1);
  // Offer at the centres of the 4 cells beside reference cell `cell`.
  void OfferBeside(const AcceptedPatch& patch, int cell, std::vector<PatchCandidate>* front);
  // Offer in `image` at the centres of its grid's `cells`, each once
  // (`cells` is sorted and deduplicated in place).
  void OfferAtCells(const AcceptedPatch& patch, int image, std::vector<int>* cells,
                    std::vector<PatchCandidate>* front);
  // A pmvs pass's rim in the patch's views: Offer at the cells beside the
  // projections of its points [first, last) in each view that may be a
  // reference and meets the reference at `patch.center` at 2 max_angle_deg
  // or more, with that view as reference. PMVS2 expands a patch in every
  // image it is seen in: a wall a few pixels wide in a nadir reference is
  // wider in the oblique view beside it.
  void OfferInViews(const AcceptedPatch& patch, const DensePoint* first, const DensePoint* last,
                    std::vector<PatchCandidate>* front);
  // The images whose cells patch p's points claim: its views, then covers_[p].
  template <typename F>
  void ForEachClaimImage(int p, F&& f) const {
    for (const int v : patches_[p].views) f(v);
    if (!covers_.empty()) {
      for (const int v : covers_[p]) f(v);
    }
  }
  // Patches emit and expand as in pmvs mode.
  bool PmvsStyle() const { return grows_as_pmvs_ || options_.mode == MatchMode::kPmvs; }
  // Frees the cells point d owns, in its reference and its patch's views.
  void Release(const DensePoint& d);
  bool IsBarrier(int image, int x, int y, const AcceptedPatch& patch) const;
  // Whether local-frame point x lies on the group's own ground.
  bool InRegion(const Eigen::Vector3d& x) const {
    return region_.Unbounded() || region_.Contains((x + group_.origin).head<2>());
  }
  // Moves out of `wave` (in order) the candidates whose centre lies within
  // window_size / 2 pixels, on both axes, of an earlier kept one's in the
  // same reference image, and returns them in order. `pixels[i]`: wave[i]'s
  // centre projected in its reference image.
  std::vector<PatchCandidate> Crowded(std::vector<PatchCandidate>* wave,
                                      const std::vector<Eigen::Vector2d>& pixels) const;
  // Accepts the evaluated candidates best score first; returns accepted indices.
  std::vector<int> AcceptBatch(std::vector<std::optional<AcceptedPatch>>& results);

  const MatchGroupData& group_;
  const MatcherOptions& options_;
  PatchEngine* engine_;  // GrowAsPmvs replaces it
  bool grows_as_pmvs_ = false;
  std::vector<Grid> grids_;
  std::vector<EdgeMap> edges_;
  GroundRegion region_;
  std::vector<AcceptedPatch> patches_;
  // Per reference image, the group's other reference images outside its
  // view list, which see its ground in a group larger than a view list;
  // empty lists everywhere otherwise, and then covers_ stays empty.
  std::vector<std::vector<int>> beyond_views_;
  std::vector<std::vector<int>> covers_;  // per patch, EmitPlan::covers
  std::vector<DensePoint> points_;
  std::vector<PatchCandidate> front_;
  size_t front_head_ = 0;  // front_[0, front_head_) is spent (RunWaves)
  // cut_[p]: RefitPlanes cut patch p back to its centre (with refill_cut it
  // expands from there); one per patch, pushed with it.
  std::vector<uint8_t> cut_;
  // Cells beside a patch's (OfferBeside, Prune), reused between patches.
  std::vector<int> beside_scratch_;
  // Emit's flags of the planned points it kept, reused between patches.
  std::vector<uint8_t> emit_scratch_;
  std::vector<std::vector<double>> seed_depths_;
  long seeds_tried_ = 0, seeds_accepted_ = 0, candidates_ = 0, waves_ = 0, largest_wave_ = 0;
  long emitted_ = 0;
};

// The pixels of the `side` x `side` window centred on pixel (cx, cy) that a
// sapmvs patch writes its points to: those 4-connected to the centre through
// pixels that are inside `grey`, not barrier(x, y), and of a grey level the
// weighted NCC gave a weight of at least min_weight (ncc_weights in ncc.cl:
// exp(-d^2 / 2 s^2), d the difference from the centre's grey level and s
// sigma_color standard deviations of the 3 x 3 pixels around it, at least
// kNccWeightMinSpread). The score was decided by the pixels like the
// centre; the others, across a roof edge or a crown's rim, were hardly
// counted, and writing the plane there fattened roofs over the ground (on
// `small`, 1.8 % of all points lay over 5 m above the ground). The centre
// comes first; with sigma_color or min_weight 0 the weights do not
// restrict.
std::vector<std::pair<int, int>> WindowPixels(const cv::Mat& grey, int cx, int cy, int side,
                                              double sigma_color, double min_weight,
                                              const std::function<bool(int, int)>& barrier);

// Intersection of the ray through pixel uv of `camera` with the plane
// through `c` with normal `n`; NaN when parallel or behind the camera.
Eigen::Vector3d IntersectPlane(const Camera& camera, const Eigen::Vector2d& uv,
                               const Eigen::Vector3d& c, const Eigen::Vector3d& n);

}  // namespace sapmvs
