# Thin wrapper over scripts/setup, CMake presets and ctest. See README.md.
.PHONY: setup build demo test dev bench fuzz clean blender-addon

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

# Fuzzes the parsers with libFuzzer (fuzz/README.md): the L-system grammar, the JSON documents
# (scenes, graphs, edit scripts), session files and mesh files, FUZZ_SECONDS each (default 300). New inputs
# go to build/fuzz/<target>-corpus; the seed corpora in the source tree are only read.
FUZZ_SECONDS ?= 300
FUZZ_FLAGS = -max_total_time=$(FUZZ_SECONDS) -timeout=30 -rss_limit_mb=4096 -print_final_stats=1
fuzz: setup
	@CC=clang CXX=clang++ cmake -S . -B build/fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTENDRIL_BUILD_FUZZ=ON \
		-DTENDRIL_BUILD_TESTS=OFF -DTENDRIL_BUILD_BENCH=OFF -DTENDRIL_BUILD_STUDIO=OFF >/dev/null
	@cmake --build build/fuzz --target lsystem_fuzz documents_fuzz session_fuzz mesh_fuzz tendril -j2
	@mkdir -p build/fuzz/lsystem-corpus build/fuzz/documents-corpus build/fuzz/session-corpus build/fuzz/mesh-corpus
	@fuzz/session/make-corpus.sh build/fuzz/tendril build/fuzz/session-seeds
	./build/fuzz/lsystem_fuzz build/fuzz/lsystem-corpus fuzz/lsystem/corpus -dict=fuzz/lsystem/lsystem.dict $(FUZZ_FLAGS)
	./build/fuzz/documents_fuzz build/fuzz/documents-corpus fuzz/documents/corpus -dict=fuzz/documents/documents.dict \
		$(FUZZ_FLAGS)
	./build/fuzz/session_fuzz build/fuzz/session-corpus build/fuzz/session-seeds $(FUZZ_FLAGS)
	LSAN_OPTIONS=suppressions=$(CURDIR)/fuzz/mesh/lsan.supp ./build/fuzz/mesh_fuzz build/fuzz/mesh-corpus fuzz/mesh/corpus -dict=fuzz/mesh/mesh.dict $(FUZZ_FLAGS)

# The Blender add-on (docs/blender.md) as a zip for Edit > Preferences > Add-ons > Install.
blender-addon:
	@mkdir -p build
	@rm -f build/tendril_blender.zip
	@cd blender && zip -qr ../build/tendril_blender.zip tendril_blender -x '*/__pycache__/*' '*.pyc'
	@echo "wrote build/tendril_blender.zip"

clean:
	rm -rf build out
