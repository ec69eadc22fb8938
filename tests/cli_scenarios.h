// Scenario texts shared by command-level tests.
#pragma once

namespace triadcal {
namespace testing_fixtures {

// The paper profile for 60 s at 50 Hz, 2 mV and 15", with the constraint
// dpsi - dlambda2 = 0; a test may append an `effects:` block.
inline constexpr const char* kPaper60sScenario = R"(
profile: {duration_s: 60, rate_hz: 50}
truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, W0y: 1504.2, W0z: 1504.3,
        dpsi: -33, dtheta_c: 43, dlambda2: -33, dx2: -7, dy2: 16, dz2: 4}
noise: {accel_mV: 2.0, angle_arcsec: 15}
run:
  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500]}
  constraints:
    - {expr: "dpsi - dlambda2", value_arcmin: 0, sigma_arcsec: 30}
)";

}  // namespace testing_fixtures
}  // namespace triadcal
