// `run --device reference` on `tiny`: the whole matcher on the CPU reference,
// with no OpenCL platform to be found, against the same run on an OpenCL
// device. The two backends differ by float32 rounding, which flips a few of
// the refinement's near-ties and so moves a few patches, and through them
// the propagation: the clouds are alike, not equal.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_test_util.h"
#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/run/cloud_merge.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

// The tolerance docs/devices.md states. A reference point agrees when an
// OpenCL point lies within kAgreeRadiusGsd full-resolution GSDs of it (the
// tiny block is matched at level 1, whose footprint is 2 GSD). Against PoCL
// 98.9 % of the reference's points and 98.8 % of PoCL's agree, and the counts
// (9,394 and 9,405) differ by 0.12 %.
constexpr double kAgreeRadiusGsd = 0.5;
constexpr double kMinAgreeingShare = 0.95;
constexpr double kMaxCountDifference = 0.02;

class ReferenceDeviceTest : public test::ScratchTest {};

TEST_F(ReferenceDeviceTest, TinyRunsWithoutOpenClAndAgreesWithTheDevice) {
  const fs::path block = test::Simulated("tiny", 1) / "block.yaml";
  const fs::path ref_out = dir_ / "reference", cl_out = dir_ / "opencl";
  // No ICD to be found: any OpenCL call would fail the run.
  const test::CliResult ref = test::RunCli(
      "-q run " + block.string() + " --out " + ref_out.string() + " --device reference",
      "OCL_ICD_VENDORS=/nonexistent OCL_ICD_FILENAMES=");
  ASSERT_EQ(ref.exit_code, 0) << ref.err;
  std::ifstream report_in(ref_out / "report.json");
  const nlohmann::json report = nlohmann::json::parse(report_in);
  EXPECT_EQ(report.at("device").at("name"), "reference") << report.at("device");
  const PointCloud ref_cloud = ReadPly(ref_out / "cloud.ply");
  ASSERT_GT(ref_cloud.points.size(), 1000u);

  if (!test::HaveOpenClDevice()) GTEST_SKIP() << "no OpenCL device to compare with";
  const test::CliResult cl = test::RunCli("-q run " + block.string() + " --out " + cl_out.string());
  ASSERT_EQ(cl.exit_code, 0) << cl.err;
  const PointCloud cl_cloud = ReadPly(cl_out / "cloud.ply");
  ASSERT_GT(cl_cloud.points.size(), 1000u);

  const double gsd = EstimateBlockGeometry(ReadBlock(block)).gsd_median;
  const double n_ref = static_cast<double>(ref_cloud.points.size());
  const double n_cl = static_cast<double>(cl_cloud.points.size());
  const double share = CountWithNeighbour(ref_cloud, cl_cloud, kAgreeRadiusGsd * gsd) / n_ref;
  const double back = CountWithNeighbour(cl_cloud, ref_cloud, kAgreeRadiusGsd * gsd) / n_cl;
  const double count_difference = std::abs(n_ref - n_cl) / n_cl;
  std::printf(
      "[ AGREE    ] reference %.0f points, OpenCL %.0f (%.2f %% apart); within %.2f GSD: %.2f %% "
      "of the reference's, %.2f %% of OpenCL's\n",
      n_ref, n_cl, 100 * count_difference, kAgreeRadiusGsd, 100 * share, 100 * back);
  EXPECT_GE(share, kMinAgreeingShare);
  EXPECT_GE(back, kMinAgreeingShare);
  EXPECT_LE(count_difference, kMaxCountDifference);
}

}  // namespace
}  // namespace sapmvs
