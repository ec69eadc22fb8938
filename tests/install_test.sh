#!/usr/bin/env bash
# ctest, label `install` (ctest -L install): `cmake --install` of the build into
# a temporary prefix, then
#   consumer  (installed_consumer): the headers are under include/triadcal/
#             only; examples/consumer configures against the prefix with
#             find_package(triadcal) while CMake may not find MPI (the package
#             must not need it), builds (#include <triadcal/...>), fits the
#             main example (paper experiment 3, seed 1) and gives the numbers
#             of `triadcal fit` from the same prefix;
#   python    (installed_python): the module is installed in the folder that
#             the interpreter itself searches for the prefix the build was
#             configured with (its sys.path with -E -s: no PYTHONPATH, no user
#             site), and imports and runs from the temporary prefix's copy.
#             Exits 77 (skipped) when the module was not built.
#   tests/install_test.sh consumer BUILD_DIR SOURCE_DIR
#   tests/install_test.sh python BUILD_DIR SOURCE_DIR PYTHON MODULE_DIR CONFIGURED_PREFIX
set -euo pipefail
mode="$1"
build="$2"
source="$3"
if [ "$mode" = python ] && [ -z "${5:-}" ]; then
  echo "install_test: the Python module was not built (pybind11-dev, python3-dev, python3-numpy): skipped"
  exit 77
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
prefix="$tmp/prefix"
cmake --install "$build" --prefix "$prefix" > "$tmp/install.log"

if [ "$mode" = python ]; then
  python="$4"
  module_dir="$5"
  configured_prefix="$6"
  ls "$prefix/$module_dir"/triadcal*.so > /dev/null
  # Where the interpreter looks on its own, for the prefix the build installs to.
  "$python" -E -s - "$configured_prefix/$module_dir" <<'PY'
import os, sys
want = os.path.normpath(sys.argv[1])
searched = [os.path.normpath(p) for p in sys.path if p]
assert want in searched, f"{want} is not on {sys.executable}'s own sys.path {searched}"
print(f"python: {want} is on {sys.executable}'s sys.path (no PYTHONPATH)")
PY
  # The installed copy imports and runs.
  "$python" -E -s - "$prefix/$module_dir" "$source/examples/paper-experiment3/scenario.yaml" <<'PY'
import os, sys
sys.path.insert(0, sys.argv[1])
import triadcal
assert os.path.dirname(triadcal.__file__) == sys.argv[1], triadcal.__file__
sim = triadcal.simulate(sys.argv[2], seed=1)
assert sim["readings_mV"].shape[1] == 3
print(f"python: import triadcal {triadcal.__version__} from {triadcal.__file__}: simulate ran")
PY
  exit 0
fi

# The headers under include/triadcal/ only, and not the command's own (tools/).
[ -f "$prefix/include/triadcal/core/model/parameters.h" ]
[ -f "$prefix/include/triadcal/solvers/estimation/batch_solver.h" ]
for d in core solvers tools; do
  [ ! -e "$prefix/include/$d" ] || { echo "install_test: $prefix/include/$d installed" >&2; exit 1; }
done
[ ! -e "$prefix/include/triadcal/tools" ] || { echo "install_test: tools/ headers installed" >&2; exit 1; }

launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# CMAKE_DISABLE_FIND_PACKAGE_MPI: a find_dependency(MPI) in the package would fail.
cmake -S "$source/examples/consumer" -B "$tmp/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_DISABLE_FIND_PACKAGE_MPI=ON "${launcher[@]}" \
  > "$tmp/configure.log" 2>&1 || { cat "$tmp/configure.log"; exit 1; }
cmake --build "$tmp/consumer" -j2 > "$tmp/build.log" || { cat "$tmp/build.log"; exit 1; }

bin="$prefix/bin/triadcal"
"$bin" simulate "$source/examples/paper-experiment3/scenario.yaml" -o "$tmp/run" --seed 1 > /dev/null
"$bin" fit "$tmp/run/run.yaml" -o "$tmp/fit.json" > /dev/null
"$tmp/consumer/fit_example" "$tmp/run/run.yaml" > "$tmp/consumer.json"

python3 - "$tmp/fit.json" "$tmp/consumer.json" <<'PY'
import json, sys
cli = json.load(open(sys.argv[1]))["parameters"]
lib = json.load(open(sys.argv[2]))
assert set(cli) == set(lib), (sorted(cli), sorted(lib))
worst = 0.0
for name, p in cli.items():
    d = abs(lib[name]["value"] - p["value"]) / p["sigma"]
    worst = max(worst, d)
    assert d <= 1e-6, f"{name}: library {lib[name]['value']} vs triadcal fit {p['value']}"
    assert abs(lib[name]["sigma"] / p["sigma"] - 1) <= 1e-6, name
    assert lib[name]["unit"] == p["unit"], name
print(f"consumer: {len(cli)} parameters as `triadcal fit`, largest difference {worst:.2e} sigma")
PY
