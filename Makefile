# Thin wrapper over scripts/setup, CMake presets and ctest. See README.md.
.PHONY: setup build demo test dev bench fuzz clean

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

# Fuzzes the L-system grammar parser and engine with libFuzzer for FUZZ_SECONDS (default 300).
# New inputs go to build/fuzz/lsystem-corpus; the seed corpus fuzz/lsystem/corpus is only read.
FUZZ_SECONDS ?= 300
fuzz: setup
	@CC=clang CXX=clang++ cmake -S . -B build/fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTENDRIL_BUILD_FUZZ=ON \
		-DTENDRIL_BUILD_TESTS=OFF -DTENDRIL_BUILD_BENCH=OFF >/dev/null
	@cmake --build build/fuzz --target lsystem_fuzz -j2
	@mkdir -p build/fuzz/lsystem-corpus
	./build/fuzz/lsystem_fuzz build/fuzz/lsystem-corpus fuzz/lsystem/corpus -dict=fuzz/lsystem/lsystem.dict \
		-max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 -print_final_stats=1

clean:
	rm -rf build out
