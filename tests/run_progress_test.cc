#include "util/run_progress.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace sapmvs {
namespace {

// What a RunProgress wrote, through a memory stream.
class Captured {
 public:
  Captured() : file_(open_memstream(&buf_, &size_)) {}
  ~Captured() {
    if (file_) std::fclose(file_);
    std::free(buf_);
  }
  std::FILE* file() { return file_; }
  std::string Text() {
    std::fflush(file_);
    return std::string(buf_, size_);
  }

 private:
  char* buf_ = nullptr;
  size_t size_ = 0;
  std::FILE* file_;
};

TEST(RunProgress, ClockShowsMinutesAndHours) {
  EXPECT_EQ(RunProgress::Clock(0), "0:00");
  EXPECT_EQ(RunProgress::Clock(59.6), "1:00");
  EXPECT_EQ(RunProgress::Clock(125), "2:05");
  EXPECT_EQ(RunProgress::Clock(3600 + 62), "1:01:02");
  EXPECT_EQ(RunProgress::Clock(-3), "0:00");
}

TEST(RunProgress, LineShowsGroupStageAndEta) {
  Captured c;
  RunProgress p(/*groups=*/2, /*images=*/10, /*enabled=*/true, c.file());
  p.StartGroup(0, 3, 4);
  p.Update({"seeds", 1, 4, "120 accepted"});
  std::string line = p.Line();
  EXPECT_EQ(line.rfind("group 1/3 (4 images)  seeds 1/4, 120 accepted  0:0", 0), 0u) << line;
  EXPECT_NE(line.find("ETA after the first group"), std::string::npos) << line;
  EXPECT_LT(p.EtaSeconds(), 0);
  // The stage change was drawn in place.
  EXPECT_NE(c.Text().find("\rgroup 1/3 (4 images)  seeds 1/4"), std::string::npos) << c.Text();

  p.EndGroup(12345);
  EXPECT_NE(c.Text().find("\rgroup 1/3: 4 images, 12345 points, 0:0"), std::string::npos)
      << c.Text();
  // 6 of 10 images left at the first group's pace.
  EXPECT_GE(p.EtaSeconds(), 0);
  // The group's measured peak beside the plan's estimate.
  p.StartGroup(1, 3, 2);
  p.EndGroup(7, 300.0 * (1 << 20), 256.0 * (1 << 20));
  EXPECT_NE(c.Text().find("group 2/3: 2 images, 7 points, 0:0"), std::string::npos) << c.Text();
  EXPECT_NE(c.Text().find(", peak 300 MiB (estimate 256 MiB)\n"), std::string::npos) << c.Text();
  p.StartGroup(2, 3, 6);
  line = p.Line();
  EXPECT_EQ(line.rfind("group 3/3 (6 images)  load", 0), 0u) << line;
  EXPECT_NE(line.find("ETA 0:0"), std::string::npos) << line;
  p.Finish();
  const std::string text = c.Text();
  EXPECT_EQ(text.back(), '\r') << "the status line is cleared before the summary";
}

TEST(RunProgress, DisabledWritesNothing) {
  Captured c;
  RunProgress p(1, 4, /*enabled=*/false, c.file());
  p.StartGroup(0, 1, 4);
  p.Update({"propagation", 1, 3, "wave 2"});
  p.EndGroup(10);
  p.Finish();
  EXPECT_TRUE(c.Text().empty()) << c.Text();
  // Its state still follows, for callers that read it.
  EXPECT_EQ(p.Line().rfind("group 1/1 (4 images)  propagation 1/3, wave 2", 0), 0u) << p.Line();
}

}  // namespace
}  // namespace sapmvs
