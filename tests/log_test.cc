#include "sapmvs/util/log.h"

#include <cpl_error.h>
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "sapmvs/util/error.h"
#include "test_util.h"
#include "util/gdal_messages.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

using test::Slurp;

TEST(Iso8601Utc, MillisecondsAndZulu) {
  const std::chrono::system_clock::time_point t{std::chrono::milliseconds(1234)};
  EXPECT_EQ(Iso8601Utc(t), "1970-01-01T00:00:01.234Z");
  const std::chrono::system_clock::time_point leap{std::chrono::seconds(951782400)};
  EXPECT_EQ(Iso8601Utc(leap), "2000-02-29T00:00:00.000Z");
}

TEST(LogOptions, NegativeVerbosityIsAProblem) {
  LogOptions o;
  EXPECT_EQ(o.Problem(), "");
  o.verbosity = -1;
  EXPECT_NE(o.Problem().find("verbosity"), std::string::npos);
}

class LogTest : public test::ScratchTest {};

TEST_F(LogTest, UnopenableFileIsOneErrorNamingIt) {
  LogOptions o;
  o.file = dir_ / "no" / "such" / "folder" / "run.log";
  try {
    StartLog(o, "sapmvs test");
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(o.file.string()), std::string::npos) << e.what();
  }
  EndLog(1);
  EXPECT_FALSE(fs::exists(o.file));
}

// GDAL's warnings become detail lines: on stderr at -v only, in the log file
// always. Its failures stay quiet (the caller reports them in its own line),
// whether the handler is the process's or pushed for one call (raster_io).
TEST_F(LogTest, GdalWarningsAreDetailLinesAndFailuresStayQuiet) {
  InstallGdalMessageHandler();
  for (const int verbosity : {0, 1}) {
    SCOPED_TRACE("verbosity " + std::to_string(verbosity));
    LogOptions o;
    o.verbosity = verbosity;
    o.file = dir_ / ("run" + std::to_string(verbosity) + ".log");
    StartLog(o, "sapmvs test");
    ::testing::internal::CaptureStderr();
    CPLError(CE_Warning, CPLE_AppDefined, "first warning %d", 1);
    CPLPushErrorHandler(GdalMessageHandler);
    CPLError(CE_Warning, CPLE_AppDefined, "second warning");
    CPLError(CE_Failure, CPLE_AppDefined, "a failure");
    CPLPopErrorHandler();
    CPLErrorReset();
    const std::string err = ::testing::internal::GetCapturedStderr();
    EndLog(0);
    if (verbosity > 0) {
      EXPECT_NE(err.find("GDAL warning: first warning 1\n"), std::string::npos) << err;
      EXPECT_NE(err.find("GDAL warning: second warning\n"), std::string::npos) << err;
    } else {
      EXPECT_EQ(err, "");
    }
    EXPECT_EQ(err.find("a failure"), std::string::npos) << err;
    const std::string log = Slurp(o.file);
    EXPECT_NE(log.find(" detail GDAL warning: first warning 1\n"), std::string::npos) << log;
    EXPECT_NE(log.find(" detail GDAL warning: second warning\n"), std::string::npos) << log;
    EXPECT_EQ(log.find("a failure"), std::string::npos) << log;
  }
}

// Whole lines of std::cout and std::cerr, each with a timestamp and where it
// went, between a start and an exit line; appended, not overwritten.
TEST_F(LogTest, CopiesStdoutAndStderrLinesWithTimestamps) {
  LogOptions o;
  o.file = dir_ / "run.log";
  for (int i = 0; i < 2; ++i) {
    StartLog(o, "sapmvs run " + std::to_string(i));
    ::testing::internal::CaptureStdout();
    ::testing::internal::CaptureStderr();
    std::cout << "result " << i << "\n"
              << "partial" << std::flush;
    std::cerr << "warning " << i << std::endl;
    const std::string err = ::testing::internal::GetCapturedStderr();
    const std::string out = ::testing::internal::GetCapturedStdout();
    // The console gets what it got without a log.
    EXPECT_EQ(out, "result " + std::to_string(i) + "\npartial");
    EXPECT_EQ(err, "warning " + std::to_string(i) + "\n");
    EndLog(i);
  }
  const std::string log = Slurp(o.file);
  const std::regex line(
      R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z (start |exit  |stdout|stderr|detail) .*)");
  std::istringstream lines(log);
  std::string l;
  int n = 0;
  while (std::getline(lines, l)) {
    EXPECT_TRUE(std::regex_match(l, line)) << l;
    ++n;
  }
  EXPECT_EQ(n, 10) << log;
  for (const std::string want :
       {"start  sapmvs run 0\n", "stdout result 0\n", "stdout partial\n", "stderr warning 0\n",
        "exit   0\n", "start  sapmvs run 1\n", "stdout result 1\n", "exit   1\n"}) {
    EXPECT_NE(log.find(want), std::string::npos) << want << " in\n" << log;
  }
}

}  // namespace
}  // namespace sapmvs
