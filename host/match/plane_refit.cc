#include "match/plane_refit.h"

#include <flann/flann.hpp>

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "match/footprint.h"
#include "sapmvs/util/parallel_for.h"

namespace sapmvs {
namespace {

// Fewest confirming centres: three points and the patch's own fix a plane
// with one degree of freedom to spare.
constexpr int kMinSupport = 3;

}  // namespace

std::vector<Eigen::Vector3d> FitPatchNormals(const MatchGroupData& group,
                                             const MatcherOptions& options,
                                             const std::vector<AcceptedPatch>& patches,
                                             const std::vector<uint8_t>& alive) {
  std::vector<Eigen::Vector3d> fitted(patches.size(), Eigen::Vector3d::Zero());
  if (options.refit_neighbours <= 0) return fitted;
  std::vector<int> ids;
  std::vector<float> xyz;
  for (size_t p = 0; p < patches.size(); ++p) {
    if (!alive[p]) continue;
    ids.push_back(static_cast<int>(p));
    for (int c = 0; c < 3; ++c) xyz.push_back(static_cast<float>(patches[p].center[c]));
  }
  if (static_cast<int>(ids.size()) <= kMinSupport) return fitted;
  const int k = std::min(options.refit_neighbours + 1, static_cast<int>(ids.size()));
  flann::Matrix<float> data(xyz.data(), ids.size(), 3);
  flann::Index<flann::L2<float>> index(data, flann::KDTreeSingleIndexParams(10));
  index.buildIndex();
  std::vector<size_t> nn(ids.size() * k);
  std::vector<float> nd(ids.size() * k);
  flann::Matrix<size_t> nn_m(nn.data(), ids.size(), k);
  flann::Matrix<float> nd_m(nd.data(), ids.size(), k);
  flann::SearchParams params(flann::FLANN_CHECKS_UNLIMITED);
  params.cores = 0;
  index.knnSearch(data, nn_m, nd_m, k, params);

  const double cos_max = std::cos(options.view_angle_deg * M_PI / 180.0);
  // Between device launches: ParallelFor's threads do not spin afterwards.
  ParallelFor(
      static_cast<long>(ids.size()),
      [&](long a) {
        const AcceptedPatch& pa = patches[ids[a]];
        const Camera& cam = group.images[pa.ref].camera;
        const double fp = Footprint(cam, pa.center);
        // Along the plane's slope: a window's reach on a surface seen obliquely.
        const double reach = (pa.size + 4) * SlopeFootprint(cam, pa.center, pa.normal);
        Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
        int support = 0;
        for (int j = 0; j < k; ++j) {
          const size_t b = nn[a * k + j];
          if (b == static_cast<size_t>(a)) continue;
          const Eigen::Vector3d d = patches[ids[b]].center - pa.center;
          const double dist = d.norm();
          // A centre within half a footprint says nothing about the slope.
          if (dist > reach || dist < 0.5 * fp) continue;
          if (std::abs(pa.normal.dot(d)) > options.refit_tolerance * fp) continue;
          scatter += d * d.transpose() / (dist * dist);
          ++support;
        }
        if (support < kMinSupport) return;
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(scatter);
        // Collinear centres (a ridge, a row along an edge) leave the plane free
        // to turn about their line.
        if (es.eigenvalues()[1] < 0.1 * es.eigenvalues()[2]) return;
        Eigen::Vector3d n = es.eigenvectors().col(0);
        const Eigen::Vector3d to_ref = (cam.center() - pa.center).normalized();
        if (n.dot(to_ref) < 0) n = -n;
        if (n.dot(to_ref) < cos_max) return;
        fitted[ids[a]] = n;
      },
      64);
  return fitted;
}

}  // namespace sapmvs
