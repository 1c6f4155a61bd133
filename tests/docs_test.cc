// The code's comments cite sections of docs/method.md by number: the page's
// name followed by "3.6", "section 6.1", "3.5, 3.6, 4.1" or "3 and 4". A
// citation of a section the page does not have points a reader nowhere. The
// needle is spelt in pieces below, so that the test's own strings are not
// taken for citations.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

const std::string kNeedle = std::string("method") + ".md";

fs::path SourceRoot() { return test::TestDir().parent_path(); }

// Section numbers of the headings of a Markdown page: "## 3. Title" gives
// "3", "### 3.10 Title" gives "3.10".
std::vector<std::string> SectionNumbers(const std::string& page) {
  std::vector<std::string> numbers;
  static const std::regex heading(R"(^#+ +([0-9]+(\.[0-9]+)*)\.? )");
  std::istringstream lines(page);
  std::string line;
  while (std::getline(lines, line)) {
    std::smatch m;
    if (std::regex_search(line, m, heading)) numbers.push_back(m[1]);
  }
  return numbers;
}

struct Citation {
  std::string where;  // path:line
  std::string section;
};

// Every section number cited after the needle in `text`: "N[.N]" optionally
// after "section(s)", then more numbers joined by "," or "and".
std::vector<Citation> CitationsIn(const std::string& text, const std::string& name) {
  static const std::regex cited(R"(^(\s+sections?)?\s+([0-9]+(\.[0-9]+)*))"
                                R"(((\s*(,|and)\s*[0-9]+(\.[0-9]+)*)*))");
  static const std::regex number(R"([0-9]+(\.[0-9]+)*)");
  std::vector<Citation> out;
  for (size_t at = text.find(kNeedle); at != std::string::npos;
       at = text.find(kNeedle, at + kNeedle.size())) {
    const std::string after = text.substr(at + kNeedle.size(), 80);
    std::smatch m;
    if (!std::regex_search(after, m, cited)) continue;  // a mention, not a citation
    const std::string where =
        name + ":" + std::to_string(1 + std::count(text.begin(), text.begin() + at, '\n'));
    out.push_back({where, m[2]});
    const std::string rest = m[4];
    for (auto it = std::sregex_iterator(rest.begin(), rest.end(), number);
         it != std::sregex_iterator(); ++it) {
      out.push_back({where, it->str()});
    }
  }
  return out;
}

// Citations in the sources, kernels and their notes, tests and tools.
std::vector<Citation> AllCitations() {
  static const std::set<std::string> kExtensions = {".h",  ".cc",    ".cpp", ".cl",
                                                    ".md", ".cmake", ".sh",  ".txt"};
  std::vector<Citation> all;
  for (const char* dir : {"host", "include", "kernels", "tests", "profiling", "scripts", "cmake"}) {
    const fs::path root = SourceRoot() / dir;
    if (!fs::is_directory(root)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
      if (!entry.is_regular_file() || !kExtensions.count(entry.path().extension().string())) {
        continue;
      }
      const std::string text = test::Slurp(entry.path());
      const std::vector<Citation> found =
          CitationsIn(text, fs::relative(entry.path(), SourceRoot()).string());
      all.insert(all.end(), found.begin(), found.end());
    }
  }
  return all;
}

TEST(Docs, CitationParserReadsEveryForm) {
  const std::vector<Citation> c = CitationsIn(
      "// a (" + kNeedle + " 3.4, 4.1) b\n// (" + kNeedle + " 3 and 4)\n// (docs: " + kNeedle +
          " section 6.1; x)\n// see docs/" + kNeedle + " for more\n",
      "f");
  std::vector<std::string> got;
  for (const Citation& x : c) got.push_back(x.where + " " + x.section);
  EXPECT_EQ(got, (std::vector<std::string>{"f:1 3.4", "f:1 4.1", "f:2 3", "f:2 4", "f:3 6.1"}));
  EXPECT_EQ(SectionNumbers("# Title\n## 1. One\n### 1.2 Two\n#### 3.10 Ten\ntext 4.1 x\n"),
            (std::vector<std::string>{"1", "1.2", "3.10"}));
}

TEST(Docs, MethodSectionsAreUnique) {
  const fs::path page = SourceRoot() / "docs" / kNeedle;
  ASSERT_TRUE(fs::exists(page)) << page;
  std::map<std::string, int> seen;
  for (const std::string& n : SectionNumbers(test::Slurp(page))) ++seen[n];
  EXPECT_GE(seen.size(), 10u) << "docs/" << kNeedle << " should have numbered sections";
  for (const auto& [n, count] : seen) EXPECT_EQ(count, 1) << "section " << n << " appears twice";
}

TEST(Docs, EveryCitedMethodSectionExists) {
  const fs::path page = SourceRoot() / "docs" / kNeedle;
  ASSERT_TRUE(fs::exists(page)) << page;
  const std::vector<std::string> numbers = SectionNumbers(test::Slurp(page));
  const std::set<std::string> sections(numbers.begin(), numbers.end());
  const std::vector<Citation> citations = AllCitations();
  // The code cites the page in many places; none found means the scan broke.
  EXPECT_GE(citations.size(), 10u);
  for (const Citation& c : citations) {
    EXPECT_TRUE(sections.count(c.section)) << c.where << " cites " << kNeedle << " " << c.section
                                           << ", which docs/" << kNeedle << " does not have";
  }
}

}  // namespace
}  // namespace sapmvs
