"""The jobs behind `triadcal filter` and `triadcal diagnose` are those of
`triadcal.filter` and `triadcal.diagnose` (app/filter_job.h,
app/diagnose_job.h): on one run, the same OUT as the command line's but for
what a writer stamps (provenance) and the time taken. A bad setting raises
triadcal.InputError with the command line's message. Run by ctest
(python_pytest) with TRIADCAL_BIN and PYTHONPATH set."""
import json
import os
import subprocess

import pytest

import triadcal

BIN = os.environ["TRIADCAL_BIN"]

# A short simulated run (20 s at 50 Hz).
SCENARIO = """\
seed: 5
profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 20, rate_hz: 50}
noise: {accel_mV: 2.0, angle_arcsec: 15}
run:
  bench: {lever_arm_mm: [138, 20, 20], angle_noise_arcsec: 15}
  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500], noise_mV: 2.0}
"""


def comparable(out):
    """An OUT without what changes from run to run (as tests/cli_test.h)."""
    return {k: v for k, v in out.items() if k not in ("provenance", "time_s")}


@pytest.fixture(scope="module")
def run_yaml(tmp_path_factory):
    d = tmp_path_factory.mktemp("jobs")
    (d / "scenario.yaml").write_text(SCENARIO)
    subprocess.run([BIN, "simulate", str(d / "scenario.yaml"), "-o", str(d / "sim")],
                   check=True, stdout=subprocess.DEVNULL)
    return str(d / "sim" / "run.yaml")


def cli_out(run_yaml, command, *options):
    out = os.path.join(os.path.dirname(run_yaml), command + ".json")
    subprocess.run([BIN, command, run_yaml, "-o", out, *options], check=True,
                   stdout=subprocess.DEVNULL)
    with open(out) as f:
        return json.load(f)


def test_filter_gives_the_out_of_the_command_line(run_yaml):
    cli = cli_out(run_yaml, "filter", "--iterations", "1")
    py = triadcal.filter(run_yaml, iterations=1)
    assert comparable(py) == comparable(cli)
    assert py["provenance"]["command_line"] == "python: triadcal.filter"


def test_diagnose_gives_the_out_of_the_command_line(run_yaml):
    candidates = "thermal_drift,angle_latency"
    cli = cli_out(run_yaml, "diagnose", "--candidates", candidates, "--max-effects", "1")
    py = triadcal.diagnose(run_yaml, candidates=candidates, max_effects=1)
    assert comparable(py) == comparable(cli)
    assert py["provenance"]["command_line"] == "python: triadcal.diagnose"


def test_bad_settings_name_the_option():
    with pytest.raises(triadcal.InputError, match=r"^--iterations: Value 0 not in range 1 to 20$"):
        triadcal.filter("unused.yaml", iterations=0)
    with pytest.raises(triadcal.InputError, match=r"^--hold/--free: 'Kx' given to both"):
        triadcal.filter("unused.yaml", hold=["Kx"], free=["Kx"])
