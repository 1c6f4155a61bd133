// The evaluation's plots: a cloud on a lattice a little coarser than the
// plot's pixels (where drawing each point into its pixel leaves a moire of
// dots and gaps) fills the dz map without gaps.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "sapmvs/evaluate/evaluate.h"
#include "test_util.h"

namespace sapmvs {
namespace {

class EvaluatePlotsTest : public test::ScratchTest {};

TEST_F(EvaluatePlotsTest, DzMapOfALatticeCoarserThanThePixelsHasNoGaps) {
  // 800 px over 100 m: 0.125 m pixels; points every 0.17 m.
  EvaluationReport r;
  r.tolerance = 1;
  r.unit = "m";
  r.rows.push_back(ErrorRow{});
  const double step = 0.17;
  for (int y = 0; y * step <= 50; ++y) {
    for (int x = 0; x * step <= 100; ++x) {
      r.points.emplace_back(500000 + x * step, 5400000 + y * step, 300);
      r.dz.push_back(0.5);
    }
  }
  WriteEvaluationPlots(r, dir_);
  const cv::Mat map = cv::imread((dir_ / "dz_map.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(map.empty());
  // The plot area: the pixels inside the black frame of the map. Every one
  // inside, a few pixels from the frame, holds the colour of dz = 0.5.
  int frame_x = -1, frame_y = -1;
  for (int x = 0; x < map.cols && frame_x < 0; ++x) {
    if (map.at<cv::Vec3b>(map.rows / 3, x) == cv::Vec3b(0, 0, 0)) frame_x = x;
  }
  for (int y = 0; y < map.rows && frame_y < 0; ++y) {
    if (map.at<cv::Vec3b>(y, frame_x + 20) == cv::Vec3b(0, 0, 0)) frame_y = y;
  }
  ASSERT_GE(frame_x, 0);
  ASSERT_GE(frame_y, 0);
  const cv::Vec3b inside = map.at<cv::Vec3b>(frame_y + 100, frame_x + 200);
  long gaps = 0, checked = 0;
  for (int y = frame_y + 8; y < frame_y + 390; ++y) {
    for (int x = frame_x + 8; x < frame_x + 790; ++x) {
      gaps += map.at<cv::Vec3b>(y, x) != inside;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100000);
  EXPECT_EQ(gaps, 0) << "of " << checked << " pixels";
  EXPECT_NE(inside, cv::Vec3b(255, 255, 255));
}

}  // namespace
}  // namespace sapmvs
