#!/usr/bin/env bash
# ctest (installed_consumer): installs the build into a temporary prefix, builds
# examples/consumer against it with find_package(triadcal), fits the main
# example (paper experiment 3, seed 1) with it and checks that it gives the
# numbers of `triadcal fit` from the same prefix.
#   tests/consumer_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build="$1"
source="$2"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

cmake --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log"
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$source/examples/consumer" -B "$tmp/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$tmp/prefix" "${launcher[@]}" > "$tmp/configure.log"
cmake --build "$tmp/consumer" -j2 > "$tmp/build.log" || { cat "$tmp/build.log"; exit 1; }

bin="$tmp/prefix/bin/triadcal"
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
