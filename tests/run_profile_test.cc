#include "run/run_profile.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "test_util.h"

namespace sapmvs {
namespace {

RunReport MadeUpReport() {
  RunReport r;
  r.device = "test device";
  r.total_seconds = 10;
  KernelTime score;
  score.launches = 4;
  score.items = 1000;
  score.ncc_evaluations = 1000;
  score.patch_size = 7;
  score.seconds = 0.5;
  score.max_seconds = 0.2;
  KernelTime refine;
  refine.launches = 2;
  refine.items = 10;
  refine.ncc_evaluations = 10 * 3 * (1 + 6 * 24);
  refine.patch_size = 21;
  refine.seconds = 2.0;
  refine.max_seconds = 1.5;
  r.stats.kernels["ncc_score 7x7"] = score;
  r.stats.kernels["patch_refine 21x21"] = refine;
  r.stats.stages = {{"load", {1.0, 0.0, 1.0}}, {"propagation", {3.0, 2.5, 5.4, 0, 5350}}};
  r.points = 1000;
  r.stages = {{"plan", 0.5, 0.4}, {"match", 4.0, 7.0}, {"merge", 2.0, 3.8}};
  return r;
}

TEST(RunProfile, KernelRatesFollowTheCostModel) {
  const std::vector<KernelProfile> k = ProfileKernels(MadeUpReport().stats);
  ASSERT_EQ(k.size(), 2u);
  EXPECT_EQ(k[0].kernel, "patch_refine 21x21");  // by device time
  const double samples = 10.0 * 3 * 145 * 21 * 21;
  EXPECT_DOUBLE_EQ(k[0].flops, samples * kNccFlopsPerSample);
  EXPECT_DOUBLE_EQ(k[0].bytes, samples * kNccBytesPerSample);
  EXPECT_DOUBLE_EQ(k[0].gflop_per_second, 1e-9 * samples * kNccFlopsPerSample / 2.0);
  EXPECT_DOUBLE_EQ(k[0].evaluations_per_second, 4350.0 / 2.0);
  EXPECT_DOUBLE_EQ(k[0].mean_ms, 1000.0);
  EXPECT_DOUBLE_EQ(k[0].max_ms, 1500.0);
  EXPECT_DOUBLE_EQ(k[1].items_per_second, 2000.0);
  EXPECT_DOUBLE_EQ(k[1].gb_per_second, 1e-9 * 1000 * 49 * kNccBytesPerSample / 0.5);
}

TEST(RunProfile, NoDeviceTimeGivesNoRates) {
  RunReport r = MadeUpReport();
  for (auto& [name, t] : r.stats.kernels) t.seconds = t.max_seconds = 0;
  for (const KernelProfile& k : ProfileKernels(r.stats)) {
    EXPECT_EQ(k.gflop_per_second, 0);
    EXPECT_EQ(k.evaluations_per_second, 0);
  }
  std::ostringstream out;
  PrintProfile(r, out);
  EXPECT_NE(out.str().find("did not profile"), std::string::npos) << out.str();
}

TEST(RunProfile, PhasesSortedByWallWithHostTime) {
  const std::vector<PhaseProfile> p = ProfilePhases(MadeUpReport());
  // The run's "match" is the matching stages summed, so it is left out.
  ASSERT_EQ(p.size(), 4u);
  EXPECT_EQ(p[0].phase, "propagation");
  EXPECT_DOUBLE_EQ(p[0].host(), 0.5);
  EXPECT_EQ(p[1].phase, "run merge");
  for (size_t i = 1; i < p.size(); ++i) EXPECT_GE(p[i - 1].wall, p[i].wall);
}

TEST(RunProfile, PhasesSayHowBusyTheyKeptTheCores) {
  std::ostringstream out;
  PrintProfile(MadeUpReport(), out);
  const std::string text = out.str();
  // propagation 5.4 / 3.0 s; the matching, (1.0 + 5.4) / (1.0 + 3.0) s,
  // without the run's own stages; the merge 3.8 / 2.0 s.
  EXPECT_NE(text.find("1.80"), std::string::npos) << text;
  EXPECT_NE(text.find("matching 4.000 s wall, CPU/wall 1.60"), std::string::npos) << text;
  const size_t merge = text.find("run merge");
  ASSERT_NE(merge, std::string::npos) << text;
  const std::string merge_line = text.substr(merge, text.find('\n', merge) - merge);
  EXPECT_NE(merge_line.find(" 1.90 "), std::string::npos) << merge_line;
}

TEST(RunProfile, PhasesCountTheWorkPerPoint) {
  std::ostringstream out;
  PrintProfile(MadeUpReport(), out);
  const std::string text = out.str();
  // propagation's 5350 evaluations over the cloud's 1000 points.
  EXPECT_NE(text.find("5.3"), std::string::npos) << text;
  EXPECT_NE(text.find("work 5350 NCC evaluations, 5.3 per point of the cloud"), std::string::npos)
      << text;
  RunReport none = MadeUpReport();
  none.points = 0;
  std::ostringstream quiet;
  PrintProfile(none, quiet);
  EXPECT_EQ(quiet.str().find("\nwork "), std::string::npos) << quiet.str();
}

class RunProfileFiles : public test::ScratchTest {};

TEST_F(RunProfileFiles, CsvAndJsonHoldEveryKernelAndPhase) {
  const RunReport r = MadeUpReport();
  WriteProfile(r, dir_ / "profile.csv");
  std::ifstream csv(dir_ / "profile.csv");
  std::string line;
  int kernels = 0, phases = 0, lines = 0;
  while (std::getline(csv, line)) {
    ++lines;
    kernels += line.rfind("kernel,", 0) == 0;
    phases += line.rfind("phase,", 0) == 0;
  }
  EXPECT_EQ(kernels, 2);
  EXPECT_EQ(phases, 4);
  EXPECT_EQ(lines, 7);  // with the header
  std::ifstream in(dir_ / "profile.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("kernels").size(), 2u);
  EXPECT_EQ(j.at("phases").size(), 4u);
  EXPECT_EQ(j.at("kernels")[0].at("kernel"), "patch_refine 21x21");
}

}  // namespace
}  // namespace sapmvs
