#include "run/run_profile.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <ostream>

#include "run/run_report.h"
#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"

namespace sapmvs {

std::vector<KernelProfile> ProfileKernels(const MatchStats& stats) {
  std::vector<KernelProfile> out;
  for (const auto& [name, t] : stats.kernels) {
    KernelProfile k;
    k.kernel = name;
    k.launches = t.launches;
    k.items = t.items;
    k.ncc_evaluations = t.ncc_evaluations;
    k.seconds = t.seconds;
    k.mean_ms = t.launches > 0 ? 1e3 * t.seconds / t.launches : 0;
    k.max_ms = 1e3 * t.max_seconds;
    const double samples = t.ncc_evaluations * t.patch_size * t.patch_size;
    k.bytes = samples * kNccBytesPerSample;
    k.flops = samples * kNccFlopsPerSample;
    if (t.seconds > 0) {
      k.items_per_second = t.items / t.seconds;
      k.evaluations_per_second = t.ncc_evaluations / t.seconds;
      k.gb_per_second = 1e-9 * k.bytes / t.seconds;
      k.gflop_per_second = 1e-9 * k.flops / t.seconds;
    }
    out.push_back(k);
  }
  std::stable_sort(out.begin(), out.end(), [](const KernelProfile& a, const KernelProfile& b) {
    return a.seconds > b.seconds;
  });
  return out;
}

std::vector<PhaseProfile> ProfilePhases(const RunReport& report) {
  std::vector<PhaseProfile> out;
  for (const auto& [name, t] : report.stats.stages) {
    out.push_back({name, t.wall, t.device, t.cpu, t.ncc_evaluations});
  }
  for (const RunReport::Stage& t : report.stages) {
    if (t.name == "match") continue;  // the stages above, summed
    out.push_back({"run " + t.name, t.wall, 0, t.cpu});
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const PhaseProfile& a, const PhaseProfile& b) { return a.wall > b.wall; });
  return out;
}

namespace {

std::string F(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

}  // namespace

void PrintProfile(const RunReport& report, std::ostream& out) {
  const std::vector<KernelProfile> kernels = ProfileKernels(report.stats);
  double device = 0;
  for (const KernelProfile& k : kernels) device += k.seconds;
  out << "\nprofile: kernels on " << report.device << ", by device time\n";
  char line[320];
  std::snprintf(line, sizeof line, "%-18s %8s %11s %12s %9s %6s %9s %9s %12s %8s %8s\n", "kernel",
                "launches", "items", "NCC evals", "total s", "share", "mean ms", "max ms",
                "NCC evals/s", "GB/s", "GFLOP/s");
  out << line;
  for (const KernelProfile& k : kernels) {
    std::snprintf(line, sizeof line,
                  "%-18s %8ld %11ld %12.4g %9.3f %5.1f%% %9.3f %9.3f %12.4g %8.2f %8.2f\n",
                  k.kernel.c_str(), k.launches, k.items, k.ncc_evaluations, k.seconds,
                  device > 0 ? 100 * k.seconds / device : 0.0, k.mean_ms, k.max_ms,
                  k.evaluations_per_second, k.gb_per_second, k.gflop_per_second);
    out << line;
  }
  if (device == 0) out << "(no device times: the queue did not profile)\n";
  // The work per output point: NCC evaluations of one window in one view
  // pair, per point of the cloud, which device speed and clock do not change.
  const double points = static_cast<double>(report.points);
  out << "\nprofile: phases, by wall time (host = wall - device; CPU/wall: the process's CPU"
         " time over the phase's wall; NCC evaluations per point of the cloud)\n";
  std::snprintf(line, sizeof line, "%-18s %10s %10s %10s %7s %9s %10s\n", "phase", "wall s",
                "device s", "host s", "share", "CPU/wall", "NCC/point");
  out << line;
  double match_wall = 0, match_cpu = 0, evaluations = 0;
  for (const PhaseProfile& p : ProfilePhases(report)) {
    const std::string busy = p.cpu > 0 && p.wall > 0 ? F("%.2f", p.cpu / p.wall) : "-";
    const std::string work =
        p.ncc_evaluations > 0 && points > 0 ? F("%.1f", p.ncc_evaluations / points) : "-";
    std::snprintf(line, sizeof line, "%-18s %10.3f %10.3f %10.3f %6.1f%% %9s %10s\n",
                  p.phase.c_str(), p.wall, p.device, p.host(),
                  report.total_seconds > 0 ? 100 * p.wall / report.total_seconds : 0.0,
                  busy.c_str(), work.c_str());
    out << line;
    evaluations += p.ncc_evaluations;
  }
  // The matching as a whole: its stages, which time their CPU (not the
  // run's own around them).
  for (const auto& [name, t] : report.stats.stages) {
    if (t.cpu > 0) {
      match_wall += t.wall;
      match_cpu += t.cpu;
    }
  }
  if (evaluations > 0 && points > 0) {
    out << "work " << F("%.4g", evaluations) << " NCC evaluations, "
        << F("%.1f", evaluations / points) << " per point of the cloud\n";
  }
  if (match_wall > 0) {
    out << "matching " << F("%.3f", match_wall) << " s wall, CPU/wall "
        << F("%.2f", match_cpu / match_wall) << "\n";
  }
  out << "total " << F("%.3f", report.total_seconds) << " s wall, " << F("%.3f", device)
      << " s in kernels ("
      << F("%.1f", report.total_seconds > 0 ? 100 * device / report.total_seconds : 0) << "%)\n";
}

void WriteProfile(const RunReport& report, const std::filesystem::path& csv) {
  const std::vector<KernelProfile> kernels = ProfileKernels(report.stats);
  const std::vector<PhaseProfile> phases = ProfilePhases(report);
  WriteStreamAtomically(csv, [&](std::ostream& f) {
    f << "kind,name,launches,items,ncc_evaluations,seconds,mean_ms,max_ms,items_per_s,"
         "ncc_evaluations_per_s,est_bytes,est_flops,gb_per_s,gflop_per_s,wall_s,device_s,host_s,"
         "cpu_s\n";
    f << std::setprecision(9);
    for (const KernelProfile& k : kernels) {
      f << "kernel," << k.kernel << "," << k.launches << "," << k.items << "," << k.ncc_evaluations
        << "," << k.seconds << "," << k.mean_ms << "," << k.max_ms << "," << k.items_per_second
        << "," << k.evaluations_per_second << "," << k.bytes << "," << k.flops << ","
        << k.gb_per_second << "," << k.gflop_per_second << ",,,,\n";
    }
    for (const PhaseProfile& p : phases) {
      f << "phase," << p.phase << ",,," << p.ncc_evaluations << ",,,,,,,,,," << p.wall << ","
        << p.device << "," << p.host() << "," << p.cpu << "\n";
    }
  });
  nlohmann::json j;
  j["device"] = report.device;
  j["total_seconds"] = report.total_seconds;
  j["kernels"] = nlohmann::json::array();
  for (const KernelProfile& k : kernels) {
    j["kernels"].push_back({{"kernel", k.kernel},
                            {"launches", k.launches},
                            {"items", k.items},
                            {"ncc_evaluations", k.ncc_evaluations},
                            {"seconds", k.seconds},
                            {"mean_ms", k.mean_ms},
                            {"max_ms", k.max_ms},
                            {"items_per_s", k.items_per_second},
                            {"ncc_evaluations_per_s", k.evaluations_per_second},
                            {"est_bytes", k.bytes},
                            {"est_flops", k.flops},
                            {"gb_per_s", k.gb_per_second},
                            {"gflop_per_s", k.gflop_per_second}});
  }
  j["phases"] = nlohmann::json::array();
  for (const PhaseProfile& p : phases) {
    j["phases"].push_back({{"phase", p.phase},
                           {"wall_s", p.wall},
                           {"device_s", p.device},
                           {"host_s", p.host()},
                           {"cpu_s", p.cpu},
                           {"ncc_evaluations", p.ncc_evaluations}});
  }
  std::filesystem::path json_path = csv;
  json_path.replace_extension(".json");
  WriteJsonFile(json_path, j);
}

}  // namespace sapmvs
