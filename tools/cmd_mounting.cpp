// `triadcal mounting RUN.yaml [-o OUT.json]`: which way the IMU sits on the
// platform, from the data (solvers/static/mounting_search.h): the proper
// signed permutations of its axes ranked by how well the readings follow
// gravity, each with its best angle-sensor zeros, and the run.yaml lines of
// the best one.
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/model/units.h"
#include "solvers/static/mounting_search.h"
#include "tools/command_util.h"
#include "tools/commands.h"

namespace triadcal {
namespace {

struct MountingArgs {
  std::string run_yaml, out_json;
  double zero_range_deg = 45.0;
};

int RunMounting(const MountingArgs& a, Session& session) {
  if (!a.out_json.empty()) CheckOutputPath(a.out_json, session);
  const LoadedRun run = LoadRun(a.run_yaml, &session);
  const std::vector<MountingFit> fits =
      SearchMountings(run.description, run.data, a.zero_range_deg * kDegToRad, 5.0 * kDegToRad);
  std::printf(
      "mounting: %zu samples; gravity misfit of each proper mounting [g], zeros fitted "
      "within +-%g deg\n",
      run.data.size(), a.zero_range_deg);
  std::printf("  %-22s %10s %10s %10s   %s\n", "axes", "misfit_g", "zero1_deg", "zero2_deg",
              "scale per g (x, y, z)");
  nlohmann::json list = nlohmann::json::array();
  for (std::size_t i = 0; i < fits.size(); ++i) {
    const MountingFit& f = fits[i];
    if (i < 6) {
      std::printf("  %-22s %10.4f %10.2f %10.2f   %.4g, %.4g, %.4g\n", f.AxesText().c_str(),
                  f.rms_g, f.zero_rad[0] / kDegToRad, f.zero_rad[1] / kDegToRad, f.scale[0],
                  f.scale[1], f.scale[2]);
    }
    list.push_back({{"axes", f.AxesText()},
                    {"misfit_g", f.rms_g},
                    {"zero_deg", {f.zero_rad[0] / kDegToRad, f.zero_rad[1] / kDegToRad}},
                    {"scale_per_g", {f.scale[0], f.scale[1], f.scale[2]}},
                    {"bias", {f.bias[0], f.bias[1], f.bias[2]}}});
  }
  // A vertical shaft recorded as a horizontal axis: no mounting fits, and
  // none is suggested.
  const std::string still = StillGravityNote(run.description, run.data);
  const MountingFit& best = fits.front();
  if (!still.empty()) {
    std::printf("\nno mounting suggested: %s\n", still.c_str());
  } else {
    std::printf("\nsuggested run.yaml lines (the zeros as offsets of the recorded angles):\n");
    std::printf("  mounting: {axes: %s}\n", best.AxesText().c_str());
    std::printf(
        "  columns: {lambda1: {source: ..., offset: %.2f}, lambda2: {source: ..., offset: "
        "%.2f}}\n",
        best.zero_rad[0] / kDegToRad, best.zero_rad[1] / kDegToRad);
  }
  if (still.empty() && fits.size() > 1 && fits[1].rms_g < 1.5 * best.rms_g) {
    std::printf("note: %s fits almost as well (%.4g g): the run does not tell them apart well\n",
                fits[1].AxesText().c_str(), fits[1].rms_g);
  }
  if (!a.out_json.empty()) {
    WriteJson({{"command", "mounting"}, {"run", a.run_yaml}, {"fits", list}}, a.out_json, session);
    std::printf("wrote %s\n", a.out_json.c_str());
  }
  return 0;
}

}  // namespace

Command AddMountingCommand(CLI::App& app) {
  auto a = std::make_shared<MountingArgs>();
  Command c;
  c.app = app.add_subcommand(
      "mounting", "Suggest the IMU mounting and the angle-sensor zeros from a run's data");
  c.app->add_option("run", a->run_yaml, "run description (run.yaml)")->required();
  c.app->add_option("-o,--output", a->out_json, "output JSON (every mounting and its fit)");
  c.app->add_option("--zero-range-deg", a->zero_range_deg, "search the zeros within +-this")
      ->capture_default_str()
      ->check(Bounded(0.0, 90.0));
  c.run = [a](Session& session) { return RunMounting(*a, session); };
  return c;
}

}  // namespace triadcal
