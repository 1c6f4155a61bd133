// The rows of docs/bad-inputs.md, section "Block, orientation and image
// files", run as they are documented: each case below breaks a small valid
// block (bad_inputs_fixture.h) one way, runs the CLI on it, and its output
// must equal the row of the same test name, word for word, exit code included.
// A row without a case, or a case without a row, fails too, so the table
// cannot drift from what sapmvs prints.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "bad_inputs_fixture.h"
#include "cli_test_util.h"
#include "test_util.h"

namespace sapmvs::test {
namespace {

namespace fs = std::filesystem;

constexpr const char* kSection = "## Block, orientation and image files";
constexpr const char* kSuite = "BadInputRow";
// Every case is run under `timeout`: a hang fails the case instead of the
// suite. No bound tighter than that: tests do not time (a loaded CI machine
// takes seconds to start a process), and a hang is what the FIFO cases test.
constexpr int kTimeoutSeconds = 60;

using Case = BadInputCase;

struct Row {
  std::string input, wrong, message, exit, test;
};

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

std::string Unquote(const std::string& s) {
  if (s.size() >= 2 && s.front() == '`' && s.back() == '`') return s.substr(1, s.size() - 2);
  return s;
}

fs::path DocPath() { return TestDir().parent_path() / "docs" / "bad-inputs.md"; }

// The rows of kSection by test name.
std::map<std::string, Row> ReadRows() {
  std::ifstream in(DocPath());
  std::map<std::string, Row> rows;
  std::string line;
  bool inside = false;
  while (std::getline(in, line)) {
    if (line.rfind("## ", 0) == 0) inside = line == kSection;
    if (!inside || line.rfind("| ", 0) != 0) continue;
    // Cells split at every | that is not escaped as \| (a message may hold
    // one).
    std::vector<std::string> cells;
    std::string cell;
    for (size_t i = 1; i < line.size(); ++i) {
      if (line[i] == '\\' && i + 1 < line.size() && line[i + 1] == '|') {
        cell += '|';
        ++i;
      } else if (line[i] == '|') {
        cells.push_back(Trim(cell));
        cell.clear();
      } else {
        cell += line[i];
      }
    }
    if (cells.size() != 5 || cells[0] == "input") continue;
    Row r{cells[0], cells[1], Unquote(cells[2]), cells[3], Unquote(cells[4])};
    rows[r.test] = r;
  }
  return rows;
}

std::string Dir(const fs::path& d) { return d.string(); }

class BadInputRow : public ::testing::Test {
 public:
  explicit BadInputRow(Case c) : case_(std::move(c)) {}

  void TestBody() override {
    const std::map<std::string, Row> rows = ReadRows();
    const fs::path dir = ScratchDir();
    case_.setup(dir);
    const CliResult r = RunCli(ReplaceAll(case_.args, "{D}", Dir(dir)),
                               "timeout " + std::to_string(kTimeoutSeconds));
    ASSERT_NE(r.exit_code, 124) << "sapmvs hung: killed after " << kTimeoutSeconds << " s";
    EXPECT_EQ(CountLines(r.err), 1) << "expected one line on stderr, got:\n" << r.err;
    std::string message = r.err;
    while (!message.empty() && message.back() == '\n') message.pop_back();
    message = ReplaceAll(message, Dir(dir), "…");
    const std::string name = std::string(kSuite) + "." + case_.name;
    std::ostringstream want;
    want << "| " << case_.input << " | " << case_.wrong << " | `" << ReplaceAll(message, "|", "\\|")
         << "` | " << r.exit_code << " | `" << name << "` |";
    const auto row = rows.find(name);
    ASSERT_NE(row, rows.end()) << "no row for " << name << " in " << DocPath()
                               << "; what sapmvs does now:\n"
                               << want.str();
    EXPECT_NE(r.exit_code, 0);
    EXPECT_EQ(row->second.message, message) << "the row should read:\n" << want.str();
    EXPECT_EQ(row->second.exit, std::to_string(r.exit_code)) << "the row should read:\n"
                                                             << want.str();
    EXPECT_EQ(row->second.input, case_.input) << "the row should read:\n" << want.str();
    EXPECT_EQ(row->second.wrong, case_.wrong) << "the row should read:\n" << want.str();
    std::error_code ec;
    fs::remove_all(dir, ec);
  }

 private:
  Case case_;
};

// Registered at start-up so that every row is its own test, named as the
// table names it.
const bool kRegistered = [] {
  for (const Case& c : BadInputCases()) {
    ::testing::RegisterTest(kSuite, c.name.c_str(), nullptr, nullptr, __FILE__, __LINE__,
                            [c]() -> ::testing::Test* { return new BadInputRow(c); });
  }
  return true;
}();

TEST(BadInputsDoc, EveryRowHasACaseAndAtLeast32Rows) {
  const std::map<std::string, Row> rows = ReadRows();
  std::map<std::string, bool> known;
  for (const Case& c : BadInputCases()) known[std::string(kSuite) + "." + c.name] = true;
  for (const auto& [test, row] : rows) {
    EXPECT_TRUE(known.count(test)) << DocPath() << ": row '" << row.input << "' names test '"
                                   << test << "', which does not exist";
  }
  EXPECT_GE(rows.size(), 32u) << DocPath() << ", section " << kSection;
}

// Each fixture untouched is a valid block, so a case's failure comes from
// what the case breaks.
TEST(BadInputsDoc, UnbrokenFixturesAreRead) {
  const fs::path dir = ScratchDir();
  WriteYamlFixture(dir / "yaml");
  WriteYamlFixture(dir / "jpeg", ".jpg");
  WriteColmapFixture(dir / "colmap");
  WriteStrechaFixture(dir / "strecha");
  WriteOpenSfmFixture(dir / "opensfm");
  WritePmvsFixture(dir / "pmvs");
  WriteMetashapeFixture(dir / "metashape");
  WritePix4dFixture(dir / "pix4d");
  WriteOpenSfmLlaFixture(dir / "opensfm_lla");
  for (const fs::path& block :
       {dir / "yaml" / "block.yaml", dir / "jpeg" / "block.yaml", dir / "colmap",
        dir / "strecha" / "cams", dir / "opensfm", dir / "pmvs", dir / "metashape" / "block.yaml",
        dir / "pix4d" / "block.yaml", dir / "opensfm_lla"}) {
    const CliResult r = RunCli("info " + block.string() + " --ground-height 0");
    EXPECT_EQ(r.exit_code, 0) << block << "\n" << r.err;
    EXPECT_EQ(r.err, "") << block;
  }
  const CliResult plan =
      RunCli("plan " + (dir / "yaml" / "block.yaml").string() + " --strategy footprint");
  EXPECT_EQ(plan.exit_code, 0) << plan.err;
  WriteCloudFixture(dir / "cloud");
  const CliResult eval = RunCli("evaluate " + (dir / "cloud" / "cloud.xyz").string() +
                                " --reference " + (dir / "cloud" / "lidar.xyz").string());
  EXPECT_EQ(eval.exit_code, 0) << eval.err;
  fs::remove_all(dir);
}

// `info` is no error for such a block, but it must say why there is no GSD
// instead of asking for a ground height the block already has.
TEST(BadInputsDoc, InfoSaysWhyCamerasLookingUpHaveNoGsd) {
  const fs::path dir = ScratchDir();
  WriteYamlFixture(dir);
  ReplaceInFile(dir / "orientation.txt", "100 0 0 0", "100 180 0 0");
  const CliResult r = RunCli("info " + (dir / "block.yaml").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("GSD            unknown: " + (dir / "block.yaml").string() +
                       ": no image sees the ground height (Z = 0.000)"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("--ground-height"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

// `run` used to match such a block and fail at the end with an internal
// "merge radius = 0"; it must stop before any work, writing nothing.
TEST(BadInputsDoc, RunRefusesCamerasLookingUpBeforeAnyWork) {
  const fs::path dir = ScratchDir();
  WriteYamlFixture(dir);
  ReplaceInFile(dir / "orientation.txt", "100 0 0 0", "100 180 0 0");
  const CliResult r =
      RunCli("run " + (dir / "block.yaml").string() + " --out " + (dir / "out").string());
  if (r.exit_code == 2) {
    SAPMVS_SKIP_WITHOUT_OPENCL("no OpenCL device, run stopped before the block: " + r.err);
  }
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(": no image sees the ground height (Z = 0.000): the optical axes of 'a', "
                       "'b' do not meet it (2 of 2 cameras look up)"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "cloud.ply"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sapmvs::test
