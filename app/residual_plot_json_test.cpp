#include "app/residual_plot_json.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace triadcal {
namespace {

// A long residual: a sine at 0.1 Hz in x, one spike in y, noise-free z.
ResidualReport LongResidual(std::size_t n, double dt) {
  ResidualReport r;
  r.series_what = "process residual of each interval as a mean acceleration in the triad frame";
  r.series_unit = "mg";
  r.dt_s = dt;
  r.f1_hz = 1.0 / 30.0;
  r.f2_hz = 1.0 / 12.0;
  const char* names[] = {"accel residual x", "accel residual y", "accel residual z"};
  for (int c = 0; c < 3; ++c) {
    ChannelReport ch;
    ch.name = names[c];
    ch.unit = "mg";
    r.channels.push_back(ch);
  }
  ChannelReport whitened;
  whitened.name = "whitened process V_x";
  whitened.unit = "1";
  r.channels.push_back(whitened);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = dt * (k + 0.5);
    r.t_s.push_back(t);
    r.channels[0].series.push_back(std::sin(2.0 * M_PI * 0.1 * t));
    r.channels[1].series.push_back(k == 4321 ? 7.5 : 0.01 * std::cos(0.37 * k));
    r.channels[2].series.push_back(0.0);
    r.channels[3].series.push_back(1.0);
  }
  return r;
}

TEST(ResidualPlotJson, ThinsLongSeriesKeepingExtremesAndPeaks) {
  const ResidualReport r = LongResidual(20000, 0.5);
  const nlohmann::json j = ResidualPlotJson(r, 600);
  // Only the three accel channels (mg); the whitened one is not drawn.
  ASSERT_EQ(j["channels"].size(), 3u);
  const auto& t = j["t_s"];
  EXPECT_LE(t.size(), 1200u);
  EXPECT_GE(t.size(), 1000u);
  EXPECT_EQ(j["channels"][1]["values"].size(), t.size());
  EXPECT_TRUE(std::is_sorted(t.begin(), t.end()));
  // The spike and the sine's extremes survive the thinning.
  const auto& y = j["channels"][1]["values"];
  EXPECT_EQ(*std::max_element(y.begin(), y.end()), 7.5);
  const auto& x = j["channels"][0]["values"];
  const std::vector<double>& raw = r.channels[0].series;
  // To the 4 significant digits kept.
  EXPECT_NEAR(*std::max_element(x.begin(), x.end()), *std::max_element(raw.begin(), raw.end()),
              5e-4);
  EXPECT_NEAR(*std::min_element(x.begin(), x.end()), *std::min_element(raw.begin(), raw.end()),
              5e-4);
  EXPECT_EQ(j["decimation"], "min and max of every 34 intervals");

  // Spectrum: at most max_points bins, the sine's peak at 0.1 Hz kept.
  const auto& f = j["spectrum"]["freq_hz"];
  const auto& p = j["spectrum"]["channels"][0]["power"];
  EXPECT_LE(f.size(), 600u);
  EXPECT_TRUE(std::is_sorted(f.begin(), f.end()));
  const auto peak = std::max_element(p.begin(), p.end()) - p.begin();
  EXPECT_NEAR(f[peak].get<double>(), 0.1, 1e-3);
  EXPECT_NEAR(j["bench_frequencies_hz"][1].get<double>(), 1.0 / 12.0, 1e-12);
}

TEST(ResidualPlotJson, ShortSeriesKeptWhole) {
  const ResidualReport r = LongResidual(180, 0.5);
  const nlohmann::json j = ResidualPlotJson(r, 600);
  EXPECT_EQ(j["t_s"].size(), 180u);
  EXPECT_EQ(j["decimation"], "none");
  EXPECT_EQ(j["spectrum"]["freq_hz"].size(), 90u);  // k = 1 .. N/2
  EXPECT_EQ(j["spectrum"]["decimation"], "none");
}

}  // namespace
}  // namespace triadcal
