# Thin wrapper over scripts/setup, CMake presets and ctest. See README.md.
.PHONY: setup build demo test dev bench clean

setup:
	@scripts/setup

build: setup
	@cmake --preset release >/dev/null
	@cmake --build --preset release

demo: build
	./build/release/tendril grow examples/scenes/default.json -o out/

test: setup
	@cmake --preset ci >/dev/null
	@cmake --build --preset ci
	@ctest --preset ci

dev: setup
	@cmake --preset dev >/dev/null
	@cmake --build --preset dev
	@ctest --preset dev

bench: build
	@cmake --preset release -DTENDRIL_BUILD_BENCH=ON >/dev/null
	@cmake --build --preset release --target tendril_bench
	./build/release/tendril_bench

clean:
	rm -rf build out
