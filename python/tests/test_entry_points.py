"""One job behind every entry point: the same run through `triadcal fit`,
`triadcal batch` and `triadcal.fit` gives the same OUT (app/fit_job.h): the
same keys and, bit for bit, the same parameters (values and sigma). Each fit
runs on one thread (batch always does) so that no sum depends on the split.
Run by ctest (python_pytest) with TRIADCAL_BIN and PYTHONPATH set."""
import json
import os
import subprocess

import pytest

import triadcal

BIN = os.environ["TRIADCAL_BIN"]

# A short simulated run (30 s at 50 Hz): each fit takes about a second.
SCENARIO = """\
seed: 11
profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 30, rate_hz: 50}
noise: {accel_mV: 2.0, angle_arcsec: 15}
run:
  sensor: {serial: "EP1", model: ADXL325}
  bench: {lever_arm_mm: [138, 20, 20], angle_noise_arcsec: 15}
  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500], noise_mV: 2.0}
  constraints:
    - {expr: "dpsi - dlambda2", value_arcmin: 0, sigma_arcsec: 30}
"""


def run_cli(*args):
    subprocess.run([BIN, *args], check=True, stdout=subprocess.DEVNULL)


@pytest.fixture(scope="module")
def outs(tmp_path_factory):
    d = tmp_path_factory.mktemp("entry")
    (d / "scenario.yaml").write_text(SCENARIO)
    run_cli("simulate", str(d / "scenario.yaml"), "-o", str(d / "sim"))
    run_yaml = str(d / "sim" / "run.yaml")
    run_cli("fit", run_yaml, "-o", str(d / "fit.json"), "--threads", "1")
    (d / "manifest.csv").write_text("serial,run\nEP1," + run_yaml + "\n")
    run_cli("batch", str(d / "manifest.csv"), "-o", str(d / "batch"), "--date", "2026-01-31")
    cli = json.load(open(d / "fit.json"))
    batch = json.load(open(d / "batch" / "EP1" / "2026-01-31" / "calibration.json"))
    py = triadcal.fit(run_yaml, threads=1)
    return cli, batch, py


def test_the_three_entry_points_give_the_same_out_keys(outs):
    cli, batch, py = outs
    keys = set(cli) - {"provenance"}  # the writer's stamp, not the job's
    assert set(batch) - {"provenance"} == keys
    assert set(py) - {"provenance"} == keys
    # Python's dict carries the provenance a written OUT carries: the tool and
    # the SHA-256 of the run and its data, the same as the command's.
    assert py["provenance"]["version"] == cli["provenance"]["version"]
    assert py["provenance"]["git_commit"]
    assert py["provenance"]["command_line"] == "python: triadcal.fit"
    sha = lambda prov: sorted((i["role"], i["sha256"]) for i in prov["inputs"])
    assert sha(py["provenance"]) == sha(cli["provenance"])
    for key in ("sigma_method", "hac", "residual_analysis", "settings", "parameters", "verdict"):
        assert key in py, key
    assert py["settings"] == cli["settings"] == batch["settings"]


def test_the_three_entry_points_give_identical_parameters(outs):
    cli, batch, py = outs
    assert len(cli["parameters"]) >= 27
    assert set(batch["parameters"]) == set(cli["parameters"]) == set(py["parameters"])
    for name, p in cli["parameters"].items():
        for other, q in (("batch", batch["parameters"][name]), ("python", py["parameters"][name])):
            assert q["value"] == p["value"], (other, name)
            assert q["sigma"] == p["sigma"], (other, name)
            assert q["unit"] == p["unit"], (other, name)
    assert batch["parameters"] == cli["parameters"]
    assert py["parameters"] == cli["parameters"]
    assert py["chi2_per_dof"] == cli["chi2_per_dof"] == batch["chi2_per_dof"]
