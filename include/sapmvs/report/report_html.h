#pragma once
// DIR/report.html: a run at a glance, as the processing reports of ODM and
// Metashape give it. One self-contained file that opens offline: the DSM
// picture with the groups' ground drawn over it, the orthophoto, the paper's
// statistics, time and memory per stage and per group, the merge, and the
// evaluation against a reference when `sapmvs evaluate --run DIR` has put
// evaluation.json (and its plots in evaluation/) beside it. Everything comes
// from the run folder's files, so the page can be made again at any time.
#include <filesystem>

namespace sapmvs {

// Writes `run_dir`/report.html atomically from report.json and the pictures
// beside it (dsm.png, ortho.png and their world files; evaluation.json and
// evaluation/*.png when present) and returns its path. Throws sapmvs::Error
// naming the file when report.json is missing or not a run's report.
std::filesystem::path WriteReportHtml(const std::filesystem::path& run_dir);

}  // namespace sapmvs
