// The options descriptions (option_spec.h): the range checks, flags, JSON and
// docs/options.md that come from them.
#include "sapmvs/util/option_spec.h"

#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <type_traits>

#include "run/options_reference.h"
#include "sapmvs/match/matcher_options.h"
#include "sapmvs/plan/grouping_options.h"
#include "sapmvs/run/cloud_dsm.h"
#include "sapmvs/run/run_options.h"
#include "test_util.h"
#include "util/option_flags.h"
#include "util/option_json.h"

namespace sapmvs {
namespace {

// A struct whose defaults pass; RunOptions also needs its two paths.
template <class Options>
Options Valid() {
  Options o;
  if constexpr (std::is_same_v<Options, RunOptions>) {
    o.block = "block.yaml";
    o.out = "out";
  }
  return o;
}

template <class Options>
int FieldCount() {
  Options o;
  int n = 0;
  VisitFields(o, [&](const auto&) { ++n; });
  return n;
}

// Sets field `k` of `o` to `value` when it is a number; returns its name, or
// "" when it is not a number or has no such bound.
template <class Options>
std::string SetField(Options* o, int k, double value) {
  std::string name;
  int i = 0;
  VisitFields(*o, [&](const auto& f) {
    using T = std::remove_pointer_t<decltype(f.value)>;
    if (i++ != k) return;
    if constexpr (std::is_same_v<T, int> || std::is_same_v<T, double>) {
      *f.value = static_cast<T>(value);
      name = f.name;
    } else if constexpr (std::is_same_v<T, std::vector<int>>) {
      f.value->front() = static_cast<int>(value);
      name = f.name;
    }
  });
  return name;
}

template <class Options>
OptionRange RangeOf(int k, bool* integer) {
  Options o;
  OptionRange r;
  int i = 0;
  VisitFields(o, [&](const auto& f) {
    using T = std::remove_pointer_t<decltype(f.value)>;
    if (i++ != k) return;
    r = f.range;
    *integer = !std::is_same_v<T, double>;
  });
  return r;
}

// Every bound of every described number: the value just outside fails the
// struct's Problem() naming the field, the bound itself (when closed) passes
// the field's own range.
template <class Options>
void ExpectEveryBoundChecked() {
  SCOPED_TRACE(typeid(Options).name());
  ASSERT_EQ(Valid<Options>().Problem(), "");
  for (int k = 0; k < FieldCount<Options>(); ++k) {
    bool integer = true;
    const OptionRange r = RangeOf<Options>(k, &integer);
    std::vector<std::pair<double, bool>> cases;  // value, inside
    const double step = integer ? 1 : 0;
    if (std::isfinite(r.min)) {
      cases.push_back(
          {r.min_open ? r.min : (integer ? r.min - step : std::nextafter(r.min, -1e300)), false});
    }
    if (std::isfinite(r.max)) {
      cases.push_back(
          {r.max_open ? r.max : (integer ? r.max + step : std::nextafter(r.max, 1e300)), false});
    }
    if (!integer && (std::isfinite(r.min) || std::isfinite(r.max))) {
      cases.push_back({std::numeric_limits<double>::quiet_NaN(), false});
      cases.push_back({std::numeric_limits<double>::infinity(), false});
    }
    for (const auto& [value, inside] : cases) {
      Options o = Valid<Options>();
      const std::string name = SetField(&o, k, value);
      if (name.empty()) continue;
      const std::string problem = o.Problem();
      EXPECT_NE(problem.find(name), std::string::npos) << name << " = " << value << ": " << problem;
      EXPECT_NE(problem.find(OptionText(value)), std::string::npos) << name << ": " << problem;
    }
  }
}

TEST(OptionSpec, EveryBoundOfEveryStructIsChecked) {
  ExpectEveryBoundChecked<MatcherOptions>();
  ExpectEveryBoundChecked<GroupingOptions>();
  ExpectEveryBoundChecked<DsmOptions>();
  ExpectEveryBoundChecked<RunOptions>();
}

TEST(OptionSpec, RangeTextSaysWhatIsAccepted) {
  EXPECT_EQ(Between(0, 6).Text(true), "in 0..6");
  EXPECT_EQ(OddBetween(3, 21).Text(true), "odd in 3..21");
  EXPECT_EQ(Interval(-1, 1, true, false).Text(false), "in (-1, 1]");
  EXPECT_EQ(AtLeast(1).Text(true), ">= 1");
  EXPECT_EQ(Above(0).Text(false), "> 0");
  EXPECT_EQ(AnyValue().Text(false), "");
  EXPECT_FALSE(OddBetween(3, 21).Contains(8, true));
  EXPECT_TRUE(OddBetween(3, 21).Contains(21, true));
  EXPECT_FALSE(AtLeast(0).Contains(std::nan(""), false));
}

// The drift the descriptions replaced: the Canny thresholds were never
// checked, and threshold_before must stay at or below threshold.
TEST(OptionSpec, CannyThresholdsAndThresholdOrderAreChecked) {
  MatcherOptions o;
  o.canny_low = -1;
  EXPECT_NE(o.Problem().find("canny_low"), std::string::npos) << o.Problem();
  o = {};
  o.canny_high = 0;
  EXPECT_NE(o.Problem().find("canny_high"), std::string::npos) << o.Problem();
  o = {};
  o.canny_low = 130;
  EXPECT_NE(o.Problem().find("canny_low <= canny_high"), std::string::npos) << o.Problem();
  o = {};
  o.threshold = 0.5;
  o.threshold_before = 0.6;
  EXPECT_NE(o.Problem().find("threshold_before <= threshold"), std::string::npos) << o.Problem();
}

// The pmvs passes are the last of the expand-filter passes: no more of them.
TEST(OptionSpec, PmvsPassesAreAtMostThePasses) {
  MatcherOptions o;
  o.expand_iterations = 2;
  o.pmvs_passes = 2;
  EXPECT_EQ(o.Problem(), "");
  o.pmvs_passes = 3;
  EXPECT_EQ(o.Problem(),
            "pmvs_passes <= expand_iterations (pmvs_passes = 3, expand_iterations = 2)");
  o.pmvs_passes = -1;
  EXPECT_NE(o.Problem().find("pmvs_passes"), std::string::npos) << o.Problem();
  o = {};
  o.pmvs_pass_view_angle_deg = 90;
  EXPECT_NE(o.Problem().find("pmvs_pass_view_angle_deg"), std::string::npos) << o.Problem();
  o = {};
  o.pmvs_pass_plane_tolerance = -0.5;
  EXPECT_NE(o.Problem().find("pmvs_pass_plane_tolerance"), std::string::npos) << o.Problem();
  o.pmvs_pass_plane_tolerance = 0;
  EXPECT_EQ(o.Problem(), "");
}

// `run` takes the flags of four structs: no flag may be described twice.
TEST(OptionSpec, FlagsAreUniqueAcrossRunsStructs) {
  std::map<std::string, std::string> seen;
  auto collect = [&](auto options, const char* owner) {
    VisitFields(options, [&](const auto& f) {
      if (!*f.flag) return;
      EXPECT_EQ(std::string(f.flag).rfind("--", 0), 0u) << f.flag;
      EXPECT_TRUE(seen.emplace(f.flag, owner).second)
          << f.flag << " in " << owner << " and " << seen[f.flag];
    });
  };
  collect(MatcherOptions{}, "MatcherOptions");
  collect(GroupingOptions{}, "GroupingOptions");
  collect(RunOptions{}, "RunOptions");
  collect(DsmOptions{}, "DsmOptions");
  EXPECT_GE(seen.size(), 36u);
}

// Each kind of flag reaches its field: numbers, lists, enums, byte sizes, a
// negated flag; the defaults stay where no flag is given.
TEST(OptionSpec, FlagsWriteTheirFields) {
  CLI::App app;
  RunOptions o;
  cli::AddOptionFlags(&app, &o.matcher);
  cli::AddOptionFlags(&app, &o.grouping);
  cli::AddOptionFlags(&app, &o);
  cli::AddOptionFlags(&app, &o.dsm);
  app.parse(
      "--mode pmvs --level 2 --threshold 0.8 --adaptive-sizes 15,7 --edges --canny-low 20 "
      "--strategy footprint --memory-budget 512M --tile-size 0.5 --tile-views 3 "
      "--las-version 1.4 --restart --dsm-fill 2 --device gpu",
      false);
  EXPECT_EQ(o.matcher.mode, MatchMode::kPmvs);
  EXPECT_EQ(o.matcher.level, 2);
  EXPECT_EQ(o.matcher.threshold, 0.8);
  EXPECT_EQ(o.matcher.adaptive_sizes, (std::vector<int>{15, 7}));
  EXPECT_TRUE(o.matcher.use_edges);
  EXPECT_EQ(o.matcher.canny_low, 20);
  EXPECT_EQ(o.matcher.canny_high, MatcherOptions{}.canny_high);
  EXPECT_EQ(o.grouping.strategy, GroupingStrategy::kFootprint);
  EXPECT_EQ(o.grouping.memory_budget, 512.0 * (1 << 20));
  EXPECT_EQ(o.grouping.tile_size, 0.5);
  EXPECT_EQ(o.grouping.tile_views, 3);
  EXPECT_EQ(o.las_version, LasVersion::k14);
  EXPECT_TRUE(o.restart);
  EXPECT_EQ(o.dsm.fill_passes, 2);
  EXPECT_EQ(o.device, "gpu");
  EXPECT_EQ(o.max_groups, 0);
}

TEST(OptionSpec, BadEnumAndByteSizeFlagsNameTheValue) {
  CLI::App app;
  GroupingOptions g;
  MatcherOptions m;
  cli::AddOptionFlags(&app, &g);
  cli::AddOptionFlags(&app, &m);
  try {
    app.parse("--mode foo", false);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "unknown matching mode 'foo': expected sapmvs or pmvs");
  }
  try {
    app.parse("--memory-budget 8Q", false);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--memory-budget: bad memory size '8Q'", 0), 0u)
        << e.what();
  }
}

TEST(OptionSpec, PlanTakesOnlyTheMatcherFieldsAPlanDependsOn) {
  CLI::App app;
  MatcherOptions m;
  cli::AddOptionFlags(&app, &m, cli::PlanMatcherFields());
  std::set<std::string> flags;
  for (const CLI::Option* opt : app.get_options()) flags.insert(opt->get_name());
  EXPECT_EQ(flags, (std::set<std::string>{"--help", "--level", "--csize", "--min-image-num",
                                          "--max-wave"}));
}

// A stand-in for an options struct that grew after version 1: `added` is
// new and matches as version 1 at 0; `setting` only acts while `added` is on.
struct GrownOptions {
  int kept = 1;
  int added = 0;
  double setting = 0.5;
};
template <class F>
void VisitFields(GrownOptions& o, F&& f) {
  f(Field(o.kept, "kept"));
  f(Field(o.added, "added").AsVersion1(0));
  f(Field(o.setting, "setting").UnusedWhen(o.added == 0));
}

TEST(OptionSpec, CheckpointJsonLeavesOutVersion1ValuesAndUnusedFields) {
  GrownOptions o;
  EXPECT_EQ(OptionsJson(o), nlohmann::json({{"kept", 1}}));
  o.setting = 2;  // still no effect while `added` is 0
  EXPECT_EQ(OptionsJson(o), nlohmann::json({{"kept", 1}}));
  o.added = 3;
  EXPECT_EQ(OptionsJson(o), nlohmann::json({{"kept", 1}, {"added", 3}, {"setting", 2.0}}));
}

// groups/plan.json of a run resumes only when its matcher record equals the
// new one: the record of the options that match as version 1 of the
// checkpoints did must stay what version 1 wrote (keys and values), and the
// defaults, which now match otherwise, must differ from it.
TEST(OptionSpec, CheckpointRecordOfTheVersion1MatchingIsTheOldOne) {
  const nlohmann::json old = nlohmann::json::parse(R"({
    "mode": "sapmvs", "level": 1, "cell_size": 2, "threshold": 0.7, "threshold_before": 0.4,
    "min_image_num": 3, "max_angle_deg": 10.0, "view_angle_deg": 60.0, "window_size": 7,
    "adaptive_sizes": [21, 15, 11, 7], "ncc_sigma_color": 3.0, "features_per_block": 8,
    "epipolar_distance": 2.0, "candidates_per_feature": 4, "canny_low": 40.0,
    "canny_high": 120.0, "use_edges": true, "max_wave": 16384, "max_waves": 0,
    "expand_iterations": 3, "score_fence": 3.0, "depth_tolerance": 3.0,
    "neighbour_radius": 4.0, "min_neighbours": 4, "plane_tolerance": 0.5,
    "plane_sigmas": 1.5, "min_cluster_size": 30})");
  MatcherOptions v1;
  v1.use_edges = true;
  v1.grow_threshold = 0;
  v1.emit_min_weight = 0;
  v1.refit_neighbours = 0;
  v1.refit_tolerance = 2;  // unused without the refit, so not recorded
  v1.refill_cut = true;    // likewise
  v1.pmvs_passes = 0;
  v1.first_features_per_block = 0;
  EXPECT_EQ(OptionsJson(v1), old) << OptionsJson(v1).dump(2);
  const nlohmann::json defaults = OptionsJson(MatcherOptions{});
  EXPECT_NE(defaults, old);
  EXPECT_EQ(defaults["emit_min_weight"], 0.3);
  EXPECT_EQ(defaults["refit_neighbours"], 16);
  EXPECT_EQ(defaults["refit_tolerance"], 0.7);
  EXPECT_FALSE(defaults.contains("refill_cut"));
  EXPECT_EQ(defaults["pmvs_passes"], 1);
  EXPECT_EQ(defaults["pmvs_pass_view_angle_deg"], 80.0);
  EXPECT_EQ(defaults["pmvs_pass_plane_tolerance"], 2.0);
  MatcherOptions refill;
  refill.refill_cut = true;
  EXPECT_EQ(OptionsJson(refill)["refill_cut"], true);
  MatcherOptions pmvs;
  pmvs.mode = MatchMode::kPmvs;
  EXPECT_EQ(OptionsJson(pmvs)["mode"], "pmvs");
  // pmvs mode matches as before: its records resume.
  EXPECT_FALSE(OptionsJson(pmvs).contains("pmvs_passes"));
  EXPECT_FALSE(OptionsJson(pmvs).contains("pmvs_pass_view_angle_deg"));
  EXPECT_FALSE(OptionsJson(pmvs).contains("pmvs_pass_plane_tolerance"));
  // A later option is recorded once it is set, so that a run matched with
  // it does not resume under another value.
  MatcherOptions sparse = v1;
  sparse.adaptive_sample_step = 2.0;
  EXPECT_EQ(OptionsJson(sparse)["adaptive_sample_step"], 2.0);
  EXPECT_NE(OptionsJson(sparse), old);
}

TEST(OptionsReference, DocsAreCurrent) {
  const std::filesystem::path doc = test::TestDir() / ".." / "docs" / "options.md";
  ASSERT_TRUE(std::filesystem::exists(doc)) << doc;
  EXPECT_TRUE(test::Slurp(doc) == OptionsReference())
      << "docs/options.md is not current: regenerate it with\n"
         "  ./build/sapmvs options-reference > docs/options.md";
}

TEST(OptionsReference, ListsEveryFlagOnce) {
  const std::string doc = OptionsReference();
  for (const char* flag : {"`--level`", "`--canny-low`", "`--tile-size`", "`--memory-budget`",
                           "`--merge-radius`", "`--dsm-fill`", "`--edges`"}) {
    const size_t at = doc.find(flag);
    EXPECT_NE(at, std::string::npos) << flag;
    EXPECT_EQ(doc.find(flag, at + 1), std::string::npos) << flag;
  }
}

}  // namespace
}  // namespace sapmvs
