"""The Python module against the command line: the main example's fit, apply,
simulate and the error messages. Run by ctest (python_pytest) with PYTHONPATH
set to the module's folder and TRIADCAL_BIN, TRIADCAL_SOURCE_DIR set."""
import json
import os
import subprocess

import numpy as np
import pytest

import triadcal

BIN = os.environ["TRIADCAL_BIN"]
SOURCE = os.environ["TRIADCAL_SOURCE_DIR"]
EXAMPLE = os.path.join(SOURCE, "examples", "paper-experiment3", "scenario.yaml")


def run_cli(*args):
    subprocess.run([BIN, *args], check=True, stdout=subprocess.DEVNULL)


def test_version_is_the_command_lines():
    """One version, project()'s in CMakeLists.txt (core/version/version.h)."""
    out = subprocess.run([BIN, "--version"], check=True, capture_output=True, text=True).stdout
    assert out == f"triadcal {triadcal.__version__}\n"


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    """The main job (examples/paper-experiment3/run.sh) through the command line."""
    out = tmp_path_factory.mktemp("exp3")
    run_cli("simulate", EXAMPLE, "-o", str(out), "--seed", "1")
    run_cli("fit", str(out / "run.yaml"), "-o", str(out / "fit.json"))
    return out


def test_fit_reproduces_the_main_example(example):
    cli = json.load(open(example / "fit.json"))
    py = triadcal.fit(str(example / "run.yaml"))
    assert py["command"] == "fit"
    assert set(py["parameters"]) == set(cli["parameters"])
    for name, p in cli["parameters"].items():
        q = py["parameters"][name]
        # The same code on the same data: equal up to the rounding of a
        # multi-threaded sum (far below a millionth of sigma).
        assert abs(q["value"] - p["value"]) <= 1e-6 * p["sigma"], name
        assert q["sigma"] == pytest.approx(p["sigma"], rel=1e-6), name
        assert q["unit"] == p["unit"]
    assert py["chi2_per_dof"] == pytest.approx(cli["chi2_per_dof"], rel=1e-9)
    # And it is the right answer: within 4 sigma of the simulated truth.
    truth = json.load(open(example / "truth.json"))["parameters"]
    for name, q in py["parameters"].items():
        assert abs(q["value"] - truth[name]) < 4 * q["sigma"], name


def test_fit_from_a_dict(example):
    run = {
        "data": str(example / "run.csv"),
        "bench": {"lever_arm_mm": [138, 20, 20], "angle_noise_arcsec": 15},
        "triad": {"scale_mV_per_g": [174, 174, 174], "bias_mV": [1500, 1500, 1500],
                  "noise_mV": 0.97},
        "constraints": [{"expr": "dpsi - dlambda2", "value_arcmin": 0, "sigma_arcsec": 30}],
    }
    from_path = triadcal.fit(str(example / "run.yaml"))
    from_dict = triadcal.fit(run)
    for name, p in from_path["parameters"].items():
        assert abs(from_dict["parameters"][name]["value"] - p["value"]) <= 1e-6 * p["sigma"]


def test_simulate_gives_the_command_line_data(example):
    sim = triadcal.simulate(EXAMPLE, seed=1)
    cli = triadcal.load_run(str(example / "run.yaml"))
    assert sim["readings_mV"].shape == (90000, 3)
    np.testing.assert_array_equal(sim["t_s"], cli["t_s"])
    np.testing.assert_array_equal(sim["readings_mV"], cli["readings_mV"])
    np.testing.assert_array_equal(sim["lambda1_deg"], cli["lambda1_deg"])
    assert sim["truth"] == json.load(open(example / "truth.json"))["parameters"]


def test_apply_matches_the_command_line(example, tmp_path):
    run_cli("apply", str(example / "fit.json"), str(example / "run.yaml"), "-o",
            str(tmp_path / "w.csv"))
    rows = [line for line in open(tmp_path / "w.csv") if not line.startswith("#")][1:]
    cli = np.loadtxt(rows, delimiter=",", usecols=(1, 2, 3))
    readings = triadcal.load_run(str(example / "run.yaml"))["readings_mV"]
    from_path = triadcal.apply(str(example / "fit.json"), readings)
    from_dict = triadcal.apply(json.load(open(example / "fit.json")), readings)
    assert np.abs(from_path - cli).max() <= 1e-12
    np.testing.assert_array_equal(from_path, from_dict)
    # At rest-like magnitudes: |W| ~ 1 g on the bench.
    assert np.median(np.linalg.norm(from_path, axis=1)) == pytest.approx(1.0, abs=0.05)


def test_bad_input_raises_the_command_line_message(tmp_path):
    missing = str(tmp_path / "missing.yaml")
    with pytest.raises(triadcal.InputError) as e:
        triadcal.fit(missing)
    assert str(e.value).startswith(missing + ": ")
    assert issubclass(triadcal.InputError, ValueError)
    cal = {"parameters": {n: 0.0 for n in ["Kx", "Ky", "Kz", "W0x", "W0y", "W0z", "alpha_x",
                                           "alpha_y", "beta_x", "beta_z", "gamma_y", "gamma_z",
                                           "Kxx", "Kxy", "Kxz", "Kyx", "Kyy", "Kyz", "Kzx",
                                           "Kzy", "Kzz"]}}
    cal["parameters"].update({"Kx": 174.0, "Ky": 174.0, "Kz": 174.0})
    with pytest.raises(triadcal.InputError) as e:
        triadcal.apply(cal, np.zeros((4, 2)))
    assert str(e.value) == "readings_mV: expected an array of shape (N, 3)"
    with pytest.raises(triadcal.InputError) as e:
        triadcal.fit({"bench": {}})
    assert str(e.value) == "run: data: missing: the data file"


# A run with a gyro triad (SPEC section 10): every gyro parameter non-zero.
GYRO_SCENARIO = """\
seed: 5
profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 40, rate_hz: 50}
truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, W0y: 1504.2, W0z: 1504.3,
        dpsi: -33, dlambda2: -33, dx2: -7,
        gyro.Kx: 1.004, gyro.Ky: 0.997, gyro.Kz: 1.002, gyro.W0x: 0.31, gyro.W0y: -0.52,
        gyro.W0z: 0.2, gyro.beta_z: 15, gyro.gamma_y: -20, gyro.Gxy: 0.05, gyro.Gzz: 0.06}
noise: {accel_mV: 2.0, angle_arcsec: 15, gyro_dps: 0.05}
run:
  bench: {lever_arm_mm: [138, 20, 20], angle_noise_arcsec: 15}
  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500], noise_mV: 2.0}
  gyro: {scale: [1, 1, 1], bias_dps: [0, 0, 0], noise_dps: 0.05}
  constraints:
    - {expr: "dpsi - dlambda2", value_arcmin: 0, sigma_arcsec: 30}
"""

GYRO_NAMES = ["gyro." + n for n in [
    "Kx", "Ky", "Kz", "W0x", "W0y", "W0z", "alpha_x", "alpha_y", "beta_x", "beta_z",
    "gamma_y", "gamma_z", "Gxx", "Gxy", "Gxz", "Gyx", "Gyy", "Gyz", "Gzx", "Gzy", "Gzz"]]


@pytest.fixture(scope="module")
def gyro_example(tmp_path_factory):
    """A simulated run with a gyro, fitted by the command line."""
    out = tmp_path_factory.mktemp("gyro")
    (out / "scenario.yaml").write_text(GYRO_SCENARIO)
    run_cli("simulate", str(out / "scenario.yaml"), "-o", str(out / "sim"))
    run_cli("fit", str(out / "sim" / "run.yaml"), "-o", str(out / "fit.json"))
    return out


def test_fit_carries_the_gyro(gyro_example):
    cli = json.load(open(gyro_example / "fit.json"))
    py = triadcal.fit(str(gyro_example / "sim" / "run.yaml"))
    assert set(py["parameters"]) == set(cli["parameters"])
    assert set(GYRO_NAMES) <= set(py["parameters"])
    for name in GYRO_NAMES:
        p, q = cli["parameters"][name], py["parameters"][name]
        assert abs(q["value"] - p["value"]) <= 1e-6 * p["sigma"], name
        assert q["unit"] == p["unit"]
    assert py["parameters"]["gyro.W0x"]["unit"] == "deg/s"


def test_apply_gyro_matches_the_command_line(gyro_example, tmp_path):
    run_yaml = str(gyro_example / "sim" / "run.yaml")
    fit = str(gyro_example / "fit.json")
    run_cli("apply", fit, run_yaml, "-o", str(tmp_path / "w.csv"))
    lines = [line for line in open(tmp_path / "w.csv") if not line.startswith("#")]
    header = lines[0].strip().split(",")
    assert header[:7] == ["t", "Wx", "Wy", "Wz", "omega_x", "omega_y", "omega_z"]
    cli = np.loadtxt(lines[1:], delimiter=",", usecols=(1, 2, 3, 4, 5, 6))
    run = triadcal.load_run(run_yaml)
    assert run["gyro_dps"].shape == run["readings_mV"].shape
    sim = triadcal.simulate(str(gyro_example / "scenario.yaml"))
    np.testing.assert_allclose(sim["gyro_dps"], run["gyro_dps"], rtol=1e-15, atol=0)
    W = triadcal.apply(fit, run["readings_mV"])
    omega = triadcal.apply_gyro(fit, run["gyro_dps"], W)
    assert np.abs(W - cli[:, :3]).max() <= 1e-12
    assert np.abs(omega - cli[:, 3:]).max() <= 1e-9
    np.testing.assert_array_equal(
        omega, triadcal.apply_gyro(json.load(open(fit)), run["gyro_dps"], W))
    # The correction matters: the raw readings differ by the biases (0.3 deg/s).
    assert np.abs(omega - run["gyro_dps"]).max() > 0.2


def test_apply_gyro_bad_input(gyro_example, example):
    fit = str(gyro_example / "fit.json")
    g = np.zeros((4, 3))
    with pytest.raises(triadcal.InputError) as e:
        triadcal.apply_gyro(str(example / "fit.json"), g, g)
    assert str(e.value) == (str(example / "fit.json") +
                            ": the calibration has no gyro parameters (gyro.Kx..gyro.Gzz)")
    with pytest.raises(triadcal.InputError) as e:
        triadcal.apply_gyro(fit, np.zeros((4, 2)), g)
    assert str(e.value) == "gyro_dps: expected an array of shape (N, 3)"
    with pytest.raises(triadcal.InputError) as e:
        triadcal.apply_gyro(fit, g, np.zeros((3, 3)))
    assert str(e.value) == "W_g: expected the 4 samples of gyro_dps, got 3"
