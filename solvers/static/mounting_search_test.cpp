// Tests of the mounting search (mounting_search.h): a simulated run of the
// paper's profile, its readings re-labelled as an IMU mounted another way, must
// give that mounting back first, with the angle-sensor zeros it was given; a
// declared mounting that fits worse gives a warning naming the better one.
#include "solvers/static/mounting_search.h"

#include <gtest/gtest.h>

#include "core/model/units.h"
#include "core/simulation/simulator.h"
#include "tests/sim_fixtures.h"

namespace triadcal {
namespace {

// The run as an IMU whose own axes are platform [+y, -z, -x] would record it:
// platform x = +IMU y, platform y = -IMU z, platform z = -IMU x.
struct Remounted {
  RunDescription run;
  RunData data;
};

Remounted RemountedRun(double zero1_deg, double zero2_deg, bool vertical_shaft = false) {
  Scenario s = testing_fixtures::PaperScenario(20.0, 60.0, 2.0, 15.0, 5);
  if (vertical_shaft) s.profile.amplitude_rad[0] = 0.0;  // the inner axis turns alone, x up
  // The zeros are told apart from the triad's own misalignment only by the
  // constraint (SPEC section 4: dlambda2 moves with gamma_y, gamma_z); with the
  // six angles at 0 the search must find the zeros themselves.
  SetFromFileUnits(s.truth_layout,
                   {{"dtheta_c", zero1_deg * 60.0},
                    {"dlambda2", zero2_deg * 60.0},
                    {"dpsi", 0.0},
                    {"alpha_x", 0.0},
                    {"alpha_y", 0.0},
                    {"beta_x", 0.0},
                    {"beta_z", 0.0},
                    {"gamma_y", 0.0},
                    {"gamma_z", 0.0}},
                   &s.truth);
  Remounted r;
  r.run = s.run;
  r.data = Simulate(s);
  // IMU readings: imu[src_i] = sign_i * platform_i.
  const int src[3] = {1, 2, 0};
  const double sign[3] = {1.0, -1.0, -1.0};
  std::vector<double> imu[3];
  for (int i = 0; i < 3; ++i) {
    imu[src[i]] = r.data.w_mV[i];
    for (double& v : imu[src[i]]) v = sign[i] * v + (sign[i] < 0 ? 3000.0 : 0.0);
  }
  // Loaded with the identity mounting declared: w_mV are the IMU's own axes.
  for (int i = 0; i < 3; ++i) r.data.w_mV[i] = imu[i];
  return r;
}

TEST(MountingSearch, FindsTheMountingAndTheZeros) {
  const Remounted r = RemountedRun(2.0, -3.0);
  const std::vector<MountingFit> fits =
      SearchMountings(r.run, r.data, 10.0 * kDegToRad, 2.0 * kDegToRad);
  ASSERT_EQ(fits.size(), 24u);
  EXPECT_EQ(fits[0].AxesText(), "[\"+y\", \"-z\", \"-x\"]");
  EXPECT_NEAR(fits[0].zero_rad[0] / kDegToRad, 2.0, 0.3);
  EXPECT_NEAR(fits[0].zero_rad[1] / kDegToRad, -3.0, 0.3);
  EXPECT_LT(fits[0].rms_g, 0.05);  // dynamic terms and the triad's own errors
  EXPECT_GT(fits[1].rms_g, 0.2);   // every other mounting is far worse
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(fits[0].scale[i], 174.0, 4.0) << i;
}

TEST(MountingSearch, DeclaredMountingThatFitsWorseIsAWarning) {
  const Remounted r = RemountedRun(0.0, 0.0);
  const std::string w = MountingWarning(r.run, r.data);
  EXPECT_EQ(
      w.rfind("mounting.axes [\"+x\", \"+y\", \"+z\"] fits the data worse (gravity misfit ", 0), 0u)
      << w;
  EXPECT_NE(w.find("than [\"+y\", \"-z\", \"-x\"] ("), std::string::npos) << w;
  // Declared right: no warning.
  RunDescription right = r.run;
  const int src[3] = {1, 2, 0};
  const double sign[3] = {1.0, -1.0, -1.0};
  RunData as_loaded = r.data;
  for (int i = 0; i < 3; ++i) {
    right.axis_source[i] = src[i];
    right.axis_sign[i] = sign[i];
    as_loaded.w_mV[i] = r.data.w_mV[src[i]];
    for (double& v : as_loaded.w_mV[i]) v *= sign[i];
  }
  EXPECT_EQ(MountingWarning(right, as_loaded), "");
}

// A vertical shaft (the outer axis still at 0: x up, the inner axis turns):
// gravity's share on each platform axis never changes, so no axis gives its
// scale and offset. Judged at the nominal ones, the mounting that puts the
// IMU's upward axis (here +y) on platform x comes first, in the four ways
// of putting the other two across the shaft (which only the shaft's small
// tilt tells apart). With scale and offset free every mounting fitted such a
// run exactly (misfit 0).
TEST(MountingSearch, VerticalShaftPutsTheUpwardAxisOnX) {
  const Remounted r = RemountedRun(0.0, 0.0, /*vertical_shaft=*/true);
  const std::vector<MountingFit> fits =
      SearchMountings(r.run, r.data, 10.0 * kDegToRad, 2.0 * kDegToRad);
  ASSERT_EQ(fits.size(), 24u);
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(fits[k].axis_source[0], 1) << fits[k].AxesText();
    EXPECT_EQ(fits[k].axis_sign[0], 1.0) << fits[k].AxesText();
    EXPECT_LT(fits[k].rms_g, 0.05) << fits[k].AxesText();
  }
  EXPECT_GT(fits[4].rms_g, 0.5) << fits[4].AxesText();
  EXPECT_EQ(StillGravityNote(r.run, r.data), "");
}

// The same shaft with its angle recorded as the outer axis's (which is
// horizontal): the angles would turn gravity, the readings do not. The note
// says so (and is the loading's warning); recorded as the inner axis, none.
TEST(MountingSearch, VerticalShaftRecordedAsTheOuterAxisIsSaid) {
  Remounted r = RemountedRun(0.0, 0.0, /*vertical_shaft=*/true);
  std::swap(r.data.lambda_rad[0], r.data.lambda_rad[1]);
  std::fill(r.data.lambda_rad[1].begin(), r.data.lambda_rad[1].end(), 0.0);
  const std::string note = StillGravityNote(r.run, r.data);
  EXPECT_EQ(note.rfind("the readings do not follow the angles: ", 0), 0u) << note;
  EXPECT_NE(note.find("record its angle as lambda2"), std::string::npos) << note;
  EXPECT_EQ(MountingWarning(r.run, r.data), note);
}

}  // namespace
}  // namespace triadcal
