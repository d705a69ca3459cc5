# The two commands a user needs: `make demo` and `make test`. Both install missing Debian
# packages first (scripts/install-deps is idempotent), then build incrementally.
BUILD      ?= build
ASAN_BUILD ?= build-asan
FUZZ_SECONDS ?= 60
FUZZ_RUNS ?= 0
JOBS       ?= $(shell nproc)
PREFIX     ?= /usr/local
CMAKE_FLAGS ?=
TROCHOMILL = $(BUILD)/bin/trochomill

.PHONY: all deps test-deps fuzz-deps build demo test test-asan fuzz bench install format clean

all: build

deps:
	@scripts/install-deps

test-deps:
	@scripts/install-deps --test

fuzz-deps:
	@scripts/install-deps --fuzz

$(BUILD)/build.ninja: | deps
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release -DTROCHOMILL_WERROR=ON $(CMAKE_FLAGS)

build: deps $(BUILD)/build.ninja
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	@scripts/demo $(TROCHOMILL) $(BUILD)/demo

test: test-deps build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# One clang build for the sanitizers and the fuzzers: the library, the CLI and the tests with
# AddressSanitizer and UndefinedBehaviorSanitizer, the library also with libFuzzer's coverage,
# so `make fuzz` links its targets against the same objects (CI builds it once). -O2: the
# sanitizer tests run a quarter faster than at -O1 (OptimizeFeed.ForceAndTorqueCapsHold 102 s
# to 75 s) for the same build time. A unity build (16 files a unit): 582 s to 369 s on 2 cores,
# the headers parsed once a unit; the Release build stays one file a unit (the build users
# get, and quick to rebuild after an edit).
$(ASAN_BUILD)/build.ninja: | fuzz-deps
	CC=clang-14 CXX=clang++-14 cmake -S . -B $(ASAN_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Debug \
	  -DCMAKE_CXX_FLAGS_DEBUG="-g -O2" -DCMAKE_UNITY_BUILD=ON -DCMAKE_UNITY_BUILD_BATCH_SIZE=16 \
	  -DTROCHOMILL_WERROR=ON -DTROCHOMILL_SANITIZE=ON -DTROCHOMILL_FUZZ=ON \
	  -DTROCHOMILL_BUILD_BENCH=OFF $(CMAKE_FLAGS)

test-asan: test-deps fuzz-deps $(ASAN_BUILD)/build.ninja
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS)

# libFuzzer targets, FUZZ_SECONDS each or FUZZ_RUNS executions each (`make fuzz
# FUZZ_SECONDS=600` for a longer run); the seeds are written by the Release build's CLI.
FUZZ_TARGETS = fuzz_job fuzz_gcode fuzz_signal fuzz_mesh fuzz_stock_mesh fuzz_forces_csv \
               fuzz_profile_csv fuzz_dxf fuzz_svg
fuzz: fuzz-deps build $(ASAN_BUILD)/build.ninja
	cmake --build $(ASAN_BUILD) -j $(JOBS) --target $(FUZZ_TARGETS)
	TROCHOMILL_CLI=$(TROCHOMILL) scripts/fuzz $(ASAN_BUILD) $(FUZZ_SECONDS) $(FUZZ_RUNS)

bench: build
	$(BUILD)/bin/trochomill_bench --benchmark_min_time=0.2

install: build
	cmake --install $(BUILD) --prefix $(PREFIX)

format:
	clang-format -i $$(git ls-files '*.cpp' '*.hpp')

clean:
	rm -rf $(BUILD) $(ASAN_BUILD)
